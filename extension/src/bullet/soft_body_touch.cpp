#include "soft_body_touch.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <set>

#include "torsion/analysis/exact_predicates.h"
#include "torsion/analysis/surface_intersections.h"
#include "torsion/bt_conversions.h"
#include "torsion/bullet/fem_body.h"
#include "torsion/contact/face_distance.h"

namespace torsion {
namespace soft_touch {  // named: the unity build shares anonymous namespaces between files
namespace {

using Swept = SoftBodyTouch::Swept;

std::vector<Triangle> facesOf(const btSoftBody& soft) {
  std::vector<Triangle> faces;
  if (soft.m_nodes.size() == 0) return faces;
  const btSoftBody::Node* first = &soft.m_nodes[0];
  faces.reserve(static_cast<size_t>(soft.m_faces.size()));
  for (int f = 0; f < soft.m_faces.size(); ++f) {
    const btSoftBody::Face& face = soft.m_faces[f];
    faces.push_back({static_cast<int>(face.m_n[0] - first), static_cast<int>(face.m_n[1] - first),
                     static_cast<int>(face.m_n[2] - first)});
  }
  return faces;
}

// The nodes at the substep's start (m_q) and end (m_x), their box, the margin; the tree refit.
void refresh(Swept& s, const btSoftBody& body, std::uint64_t round) {
  const int n = body.m_nodes.size();
  s.start.resize(3 * n);
  s.end.resize(3 * n);
  s.lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  s.hi = -s.lo;
  for (int i = 0; i < n; ++i) {
    s.start.segment<3>(3 * i) = toEigen(body.m_nodes[i].m_q);
    s.end.segment<3>(3 * i) = toEigen(body.m_nodes[i].m_x);
    s.lo = s.lo.cwiseMin(s.start.segment<3>(3 * i)).cwiseMin(s.end.segment<3>(3 * i));
    s.hi = s.hi.cwiseMax(s.start.segment<3>(3 * i)).cwiseMax(s.end.segment<3>(3 * i));
  }
  s.margin = static_cast<double>(body.getCollisionShape()->getMargin());
  if (s.tree) s.tree->refit(s.start, s.end, 0);
  s.round = round;
}

bool boxesApart(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Swept& s) {
  return (lo.array() > s.hi.array()).any() || (hi.array() < s.lo.array()).any();
}

// Crossings of the segment p q with the surface at its end positions, mod 2: 1 or 0, or -1 when
// the segment grazes an edge, a corner or a plane (then another direction decides).
int crossingParity(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Swept& s,
                   std::vector<int>& candidates) {
  s.tree->query(p.cwiseMin(q), p.cwiseMax(q), candidates);
  int crossings = 0;
  for (int t : candidates) {
    const Triangle& tri = s.tree->triangles()[static_cast<size_t>(t)];
    const Eigen::Vector3d a = s.end.segment<3>(3 * tri[0]);
    const Eigen::Vector3d b = s.end.segment<3>(3 * tri[1]);
    const Eigen::Vector3d c = s.end.segment<3>(3 * tri[2]);
    const int sp = orient3dSign(a, b, c, p), sq = orient3dSign(a, b, c, q);
    if (sp == sq && sp != 0) continue;
    if (sp == 0 || sq == 0) return -1;
    const int e[3] = {orient3dSign(p, q, a, b), orient3dSign(p, q, b, c), orient3dSign(p, q, c, a)};
    if (e[0] == e[1] && e[1] == e[2]) {
      ++crossings;
      continue;
    }
    const bool some_positive = e[0] > 0 || e[1] > 0 || e[2] > 0;
    const bool some_negative = e[0] < 0 || e[1] < 0 || e[2] < 0;
    if (!(some_positive && some_negative)) return -1;  // through an edge or a corner
  }
  return crossings % 2;
}

// Whether p lies inside the closed surface (at its end positions): the parity of a ray's
// crossings, the ray tilted off the axes and another tried when one grazes a feature.
bool insideClosedSurface(const Eigen::Vector3d& p, const Swept& s, std::vector<int>& candidates) {
  if (boxesApart(p, p, s)) return false;
  static const Eigen::Vector3d kDirections[] = {{0.0131, 0.0227, 1},  {-0.0219, 0.0113, -1},
                                                {1, 0.0173, -0.0241}, {-1, -0.0157, 0.0199},
                                                {0.0163, 1, 0.0271},  {0.0251, -1, -0.0139}};
  const double reach = (s.hi - s.lo).norm() + 1.0;  // beyond the box, whichever way
  for (const Eigen::Vector3d& d : kDirections) {
    const int parity = crossingParity(p, p + reach * d, s, candidates);
    if (parity >= 0) return parity == 1;
  }
  return false;
}

// Whether a node of `a` comes within both margins of a triangle of `b` (at the substep's start or
// end), or its motion crosses one, or (b closed) it ends inside b.
bool nodesMeetTriangles(const Swept& a, const Swept& b, bool b_closed,
                        std::vector<int>& candidates) {
  if (!b.tree) return false;
  const double r = a.margin + b.margin;
  const Eigen::Vector3d pad = Eigen::Vector3d::Constant(r);
  for (int i : a.nodes) {
    const Eigen::Vector3d p0 = a.start.segment<3>(3 * i);
    const Eigen::Vector3d p1 = a.end.segment<3>(3 * i);
    const Eigen::Vector3d lo = p0.cwiseMin(p1) - pad, hi = p0.cwiseMax(p1) + pad;
    if (boxesApart(lo, hi, b)) continue;
    b.tree->query(lo, hi, candidates);
    for (int t : candidates) {
      const Triangle& tri = b.tree->triangles()[static_cast<size_t>(t)];
      for (const Eigen::VectorXd* x : {&b.start, &b.end}) {
        const Eigen::Vector3d& p = x == &b.start ? p0 : p1;
        const Eigen::Vector3d u = x->segment<3>(3 * tri[0]);
        const Eigen::Vector3d v = x->segment<3>(3 * tri[1]);
        const Eigen::Vector3d w = x->segment<3>(3 * tri[2]);
        if ((closestPointOnTriangle(p, u, v, w) - p).squaredNorm() <= r * r) return true;
        if (segmentMeetsTriangle(p0, p1, {u, v, w})) return true;
      }
    }
    if (b_closed && insideClosedSurface(p1, b, candidates)) return true;
  }
  return false;
}

}  // namespace
}  // namespace soft_touch

SoftBodyTouch::SoftBodyTouch() = default;
SoftBodyTouch::~SoftBodyTouch() = default;

SoftBodyTouch::Swept& SoftBodyTouch::sweptFem(FemBody& fem) {
  std::unique_ptr<Swept>& slot = fem_[&fem];
  if (!slot) {
    slot = std::make_unique<Swept>();
    slot->nodes = fem.model().mesh().surfaceNodes();
    slot->tree = std::make_unique<SurfaceTree>(fem.model().mesh().surfaceTriangles());
  }
  if (slot->round != round_) soft_touch::refresh(*slot, *fem.softBody(), round_);
  return *slot;
}

SoftBodyTouch::Swept& SoftBodyTouch::sweptSoft(btSoftBody& soft) {
  std::unique_ptr<Swept>& slot = soft_[&soft];
  if (!slot) slot = std::make_unique<Swept>();
  if (slot->round != round_) {
    // Bullet's bodies may change between substeps (the user appends nodes or faces).
    std::vector<Triangle> faces = soft_touch::facesOf(soft);
    if (faces.empty()) {
      slot->tree.reset();
    } else if (!slot->tree || slot->tree->triangles() != faces) {
      slot->tree = std::make_unique<SurfaceTree>(std::move(faces));
    }
    slot->nodes.resize(static_cast<size_t>(soft.m_nodes.size()));
    std::iota(slot->nodes.begin(), slot->nodes.end(), 0);
    soft_touch::refresh(*slot, soft, round_);
  }
  return *slot;
}

bool SoftBodyTouch::touches(FemBody& fem, btSoftBody& soft) {
  Swept& f = sweptFem(fem);
  Swept& s = sweptSoft(soft);
  const Eigen::Vector3d pad = Eigen::Vector3d::Constant(f.margin + s.margin);
  if (soft_touch::boxesApart(s.lo - pad, s.hi + pad, f)) return false;
  return soft_touch::nodesMeetTriangles(s, f, /*b_closed=*/true, candidates_) ||
         soft_touch::nodesMeetTriangles(f, s, /*b_closed=*/false, candidates_);
}

void SoftBodyTouch::forget(const FemBody* fem) {
  fem_.erase(fem);
}

void SoftBodyTouch::keepOnly(const btAlignedObjectArray<btSoftBody*>& bullet_bodies) {
  if (soft_.empty()) return;
  std::set<const btSoftBody*> alive;
  for (int i = 0; i < bullet_bodies.size(); ++i)
    alive.insert(bullet_bodies[i]);
  for (auto it = soft_.begin(); it != soft_.end();) {
    it = alive.count(it->first) != 0 ? std::next(it) : soft_.erase(it);
  }
}

}  // namespace torsion
