#include "torsion/contact/surface_candidates.h"

#include <algorithm>
#include <cmath>

namespace torsion {

namespace {

// When on the path a gap of g0 at the start and g1 at the end reaches the margin: now, at the
// crossing, at the end; none if apart all along.
std::optional<double> meetingTime(double g0, double g1, double margin) {
  if (g0 <= margin) return 0.0;
  if (g1 < 0) return g0 / (g0 - g1);
  if (g1 <= margin) return 1.0;
  return std::nullopt;
}

}  // namespace

SurfaceEdges::SurfaceEdges(const std::vector<Triangle>& triangles) {
  std::vector<std::pair<std::array<int, 2>, int>> halves;  // (sorted corners, triangle)
  for (size_t t = 0; t < triangles.size(); ++t) {
    for (size_t a = 0; a < 3; ++a) {
      std::array<int, 2> e = {triangles[t][a], triangles[t][(a + 1) % 3]};
      if (e[0] > e[1]) std::swap(e[0], e[1]);
      halves.emplace_back(e, static_cast<int>(t));
    }
  }
  std::sort(halves.begin(), halves.end());
  triangle_edges.assign(triangles.size(), {});
  for (size_t k = 0; k < halves.size(); ++k) {
    if (k == 0 || halves[k].first != halves[k - 1].first) {
      edges.push_back(halves[k].first);
      edge_triangles.push_back({halves[k].second, -1});
    } else if (edge_triangles.back()[1] < 0) {
      edge_triangles.back()[1] = halves[k].second;
    }
    triangle_edges[static_cast<size_t>(halves[k].second)].push_back(static_cast<int>(edges.size()) -
                                                                    1);
  }
}

Eigen::Vector3d SurfaceEdges::outwardNormal(int edge, const std::vector<Triangle>& triangles,
                                            const Eigen::VectorXd& x) const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int t : edge_triangles[static_cast<size_t>(edge)]) {
    if (t < 0) continue;
    const Triangle& tri = triangles[static_cast<size_t>(t)];
    const Eigen::Vector3d a = x.segment<3>(3 * tri[0]);
    sum += (x.segment<3>(3 * tri[1]) - a).cross(x.segment<3>(3 * tri[2]) - a).normalized();
  }
  return sum.normalized();
}

double SurfaceEdges::foldCosine(int edge, const std::vector<Triangle>& triangles,
                                const Eigen::VectorXd& x) const {
  const std::array<int, 2>& on = edge_triangles[static_cast<size_t>(edge)];
  if (on[1] < 0) return -1;
  Eigen::Vector3d n[2];
  for (size_t k = 0; k < 2; ++k) {
    const Triangle& tri = triangles[static_cast<size_t>(on[k])];
    const Eigen::Vector3d a = x.segment<3>(3 * tri[0]);
    n[k] = (x.segment<3>(3 * tri[1]) - a).cross(x.segment<3>(3 * tri[2]) - a).normalized();
  }
  return n[0].dot(n[1]);
}

Eigen::Vector3d projectionWeights(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                  const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d e0 = b - a, e1 = c - a, d = p - a;
  const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1);
  const double d20 = d.dot(e0), d21 = d.dot(e1);
  const double det = d00 * d11 - d01 * d01;
  const double v = (d11 * d20 - d01 * d21) / det;
  const double w = (d00 * d21 - d01 * d20) / det;
  return {1.0 - v - w, v, w};
}

std::optional<NodeTriangleHit> nodeTriangleCandidate(
    const std::array<Eigen::Vector3d, 2>& p, const std::array<Eigen::Vector3d, 3>& triangle0,
    const std::array<Eigen::Vector3d, 3>& triangle1, const CandidateRules& rules, bool held,
    const ExclusionRule& excluded) {
  const Eigen::Vector3d &xp = p[0], &ep = p[1];
  const Eigen::Vector3d &a0 = triangle0[0], &b0 = triangle0[1], &c0 = triangle0[2];
  Eigen::Vector3d n0 = (b0 - a0).cross(c0 - a0);
  if (!(n0.norm() > 0)) return std::nullopt;  // degenerate: no plane to stay out of
  n0.normalize();
  const double g0 = n0.dot(xp - a0);
  const double shortest = std::min({(b0 - a0).norm(), (c0 - b0).norm(), (a0 - c0).norm()});
  if (g0 < -rules.max_depth * shortest) return std::nullopt;  // the far side of the body
  // Behind the plane beyond the crease depth: only a contact already held last step is still one
  // (it sank within its tolerance); a new pair there is a node across a sharp convex crease
  // (behind the plane, not through the surface), which a contact would throw out violently.
  if (g0 < -rules.crease_depth && !held) return std::nullopt;
  if (excluded && !held && excluded(n0, g0)) return std::nullopt;
  const Eigen::Vector3d &a1 = triangle1[0], &b1 = triangle1[1], &c1 = triangle1[2];
  Eigen::Vector3d n1 = (b1 - a1).cross(c1 - a1);
  if (!(n1.norm() > 0)) n1 = n0;
  const double g1 = n1.normalized().dot(ep - a1);
  const std::optional<double> s = meetingTime(g0, g1, rules.margin);
  if (!s) return std::nullopt;
  const double when = *s;
  const Eigen::Vector3d w = projectionWeights(xp + when * (ep - xp), a0 + when * (a1 - a0),
                                              b0 + when * (b1 - b0), c0 + when * (c1 - c0));
  if (!w.allFinite() || w.minCoeff() < -kFaceInsideTolerance) return std::nullopt;
  NodeTriangleHit hit;
  hit.normal = n0;
  hit.gap = g0;
  hit.when = when;
  hit.weights = w;
  return hit;
}

bool closestPointsOfLines(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                          const Eigen::Vector3d& c, const Eigen::Vector3d& d, double& u, double& v,
                          double& distance) {
  const Eigen::Vector3d d1 = b - a, d2 = d - c, w = a - c;
  const double aa = d1.dot(d1), bb = d1.dot(d2), cc = d2.dot(d2), dd = d1.dot(w), ee = d2.dot(w);
  const double denominator = aa * cc - bb * bb;
  if (!(denominator > 1e-12 * aa * cc)) return false;
  u = (bb * ee - cc * dd) / denominator;
  v = (aa * ee - bb * dd) / denominator;
  distance = (a + u * d1 - c - v * d2).norm();
  return true;
}

std::optional<EdgeEdgeHit> edgeEdgeCandidate(
    const std::array<std::array<Eigen::Vector3d, 2>, 2>& e,
    const std::array<std::array<Eigen::Vector3d, 2>, 2>& f, const CandidateRules& rules,
    const std::function<const Eigen::Vector3d*()>& held_multiplier,
    const std::function<Eigen::Vector3d()>& outward, const ExclusionRule& excluded) {
  const double margin = rules.margin;
  const Eigen::Vector3d &p0 = e[0][0], &q0 = e[0][1], &p1 = e[1][0], &q1 = e[1][1];
  const Eigen::Vector3d &r0 = f[0][0], &s0 = f[0][1], &r1 = f[1][0], &s1 = f[1][1];
  // Normal: across both edges, pointing from edge f to edge e at the start.
  Eigen::Vector3d n0 = (q0 - p0).cross(s0 - r0);
  const double scale = (q0 - p0).norm() * (s0 - r0).norm();
  if (!(n0.norm() > 1e-3 * scale)) return std::nullopt;  // nearly parallel: nodes and faces hold
  n0.normalize();
  double g0 = n0.dot(p0 - r0);
  {
    // Cheap rejection first: apart now and at the end of the path, on the same side.
    const Eigen::Vector3d m1 = (q1 - p1).cross(s1 - r1);
    const double h1 = m1.norm() > 0 ? m1.normalized().dot(p1 - r1) : g0;
    if (std::abs(g0) > margin && std::abs(h1) > margin &&
        (g0 > 0) == (m1.dot(n0) >= 0 ? h1 > 0 : h1 < 0))
      return std::nullopt;
  }
  if (std::abs(g0) <= margin) {
    // Within the margin now, whichever way the normal turns: the pair is judged at the start,
    // so its closest points can rule it out before the (dearer) orientation. Neighbouring
    // edges of one face lie in a plane and end here.
    double u, v, distance;
    if (!closestPointsOfLines(p0, q0, r0, s0, u, v, distance)) return std::nullopt;
    if (!(u > 0 && u < 1 && v > 0 && v < 1) || distance > margin) return std::nullopt;
  }
  // Oriented out of f's surface into e's: the sign of the gap alone is arbitrary for edges lying
  // in one plane, as those of two faces pressed together do, and a wrong sign pushes one face
  // into the other. A pair held last step (which may have crossed within the tolerance) keeps
  // the side its impulse pushed.
  const Eigen::Vector3d* held = held_multiplier ? held_multiplier() : nullptr;
  const Eigen::Vector3d facing = outward();
  const double side = held != nullptr ? n0.dot(*held) : n0.dot(facing);
  if (held == nullptr && std::abs(side) < 0.5 * facing.norm()) return std::nullopt;  // not facing
  if (side < 0) {
    n0 = -n0;
    g0 = -g0;
  }
  if (g0 < -rules.crease_depth && held == nullptr) return std::nullopt;  // crossed, or apart
  if (g0 < -rules.max_depth * (q0 - p0).norm()) return std::nullopt;
  if (excluded && held == nullptr && excluded(n0, g0)) return std::nullopt;
  Eigen::Vector3d n1 = (q1 - p1).cross(s1 - r1);
  if (n1.dot(n0) < 0) n1 = -n1;
  if (!(n1.norm() > 0)) n1 = n0;
  const double g1 = n1.normalized().dot(p1 - r1);
  const std::optional<double> s = meetingTime(g0, g1, margin);
  if (!s) return std::nullopt;
  const double when = *s;
  // Closest points of the two lines at that moment; both must lie inside their edges.
  const Eigen::Vector3d a = p0 + when * (p1 - p0), b = q0 + when * (q1 - q0);
  const Eigen::Vector3d c = r0 + when * (r1 - r0), d = s0 + when * (s1 - s0);
  double u, v, distance;
  if (!closestPointsOfLines(a, b, c, d, u, v, distance)) return std::nullopt;
  if (!(u > 0 && u < 1 && v > 0 && v < 1)) return std::nullopt;
  // Closer at the start than the margin, or crossing on the path, but not closer than the
  // points: a pair whose lines pass near while the edges stay apart is no contact.
  if (when == 0 && distance > margin) return std::nullopt;
  EdgeEdgeHit hit;
  hit.normal = n0;
  hit.gap = g0;
  hit.u = u;
  hit.v = v;
  return hit;
}

}  // namespace torsion
