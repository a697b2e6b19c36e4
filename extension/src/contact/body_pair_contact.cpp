#include "torsion/contact/body_pair_contact.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "torsion/contact/surface_candidates.h"
#include "torsion/format_number.h"

namespace torsion {

namespace {

// A node pairs with a triangle only where its body's surface faces the triangle: its normal
// (n_p, the mean of its surface triangles' normals) against the triangle's, n_p . n below
// -kFacing. A node whose surface runs along the face cannot be pushed out through it: on a soft
// incline the slab's top nodes just ahead of a sliding block (a tenth of a millimetre above its
// sunk-in bottom) paired with the block's front face, and that horizontal contact stopped the
// block dead at the first node line (docs/contact.md, "Friction between FEM bodies").
constexpr double kFacing = 0.25;
// ... and only for a node already touching it: within this many gap tolerances of its plane.
constexpr double kFacingBand = 4;
// An edge whose two triangles' normals are within 20 degrees lies on a flat part of its surface.
const double kFlatFold = std::cos(20.0 * M_PI / 180.0);

// 3n: each surface node's unit outward normal at positions x (zero off the surface): the sum of
// its surface triangles' area-weighted normals.
void nodeNormals(const TetMesh& mesh, const Eigen::VectorXd& x, Eigen::VectorXd& normals) {
  normals.setZero(x.size());
  for (const Triangle& t : mesh.surfaceTriangles()) {
    const Eigen::Vector3d a = x.segment<3>(3 * t[0]);
    const Eigen::Vector3d n = (x.segment<3>(3 * t[1]) - a).cross(x.segment<3>(3 * t[2]) - a);
    for (int corner : t)
      normals.segment<3>(3 * corner) += n;
  }
  for (Eigen::Index i = 0; i < normals.size() / 3; ++i) {
    const double length = normals.segment<3>(3 * i).norm();
    if (length > 0) normals.segment<3>(3 * i) /= length;
  }
}

// Whether node x, whose surface does not face the triangle (its normal against the triangle's,
// n_p . n above -kFacing), lies at the triangle's rim: its projection within kRimBand of the
// triangle's perimeter. Such a node sits in the plane the two bodies touch along, at the edge of
// the other body's side face (a slab's top node just ahead of a sliding block's front face): a
// contact there holds the block against its own contact plane, a wall in its path (measured: a
// soft block sliding down a soft incline stopped dead at the first node line, 0.15 m/s to 0 within
// two steps). A node meeting a face head-on, or crossing into it on its path, projects inside.
constexpr double kRimBand = 0.02;  // of the triangle's shortest altitude
bool grazesRim(const Eigen::Vector3d& x, const std::array<Eigen::Vector3d, 3>& t,
               const Eigen::Vector3d& node_normal, const Eigen::Vector3d& normal) {
  if (node_normal.dot(normal) <= -kFacing) return false;
  const Eigen::Vector3d w = projectionWeights(x, t[0], t[1], t[2]);
  if (!w.allFinite()) return false;
  const double twice_area = (t[1] - t[0]).cross(t[2] - t[0]).norm();
  double nearest = std::numeric_limits<double>::infinity(), lowest = nearest;
  for (int i = 0; i < 3; ++i) {
    const double edge =
        (t[static_cast<size_t>((i + 2) % 3)] - t[static_cast<size_t>((i + 1) % 3)]).norm();
    const double altitude = twice_area / edge;
    nearest = std::min(nearest, w[i] * altitude);
    lowest = std::min(lowest, altitude);
  }
  return nearest <= kRimBand * lowest;
}

double meanSurfaceEdge(const TetMesh& mesh) {
  const std::vector<Triangle>& triangles = mesh.surfaceTriangles();
  if (triangles.empty()) return 0;
  double sum = 0;
  for (const Triangle& t : triangles) {
    for (size_t k = 0; k < 3; ++k)
      sum += (mesh.restPositions()[static_cast<size_t>(t[k])] -
              mesh.restPositions()[static_cast<size_t>(t[(k + 1) % 3])])
                 .norm();
  }
  return sum / (3.0 * static_cast<double>(triangles.size()));
}

}  // namespace

Status BodyContactSettings::validate() const {
  if (!(std::isfinite(friction) && friction >= 0))
    return Error{"fem_contact: friction = " + formatNumber(friction) + ": must be >= 0"};
  if (!(std::isfinite(gap_tolerance) && gap_tolerance >= 0))
    return Error{"fem_contact: gap_tolerance = " + formatNumber(gap_tolerance) +
                 ": must be >= 0 m (0: from the meshes)"};
  if (!(std::isfinite(thickness_factor) && thickness_factor >= 0))
    return Error{"fem_contact: thickness_factor = " + formatNumber(thickness_factor) +
                 ": must be >= 0 (times gap_tolerance)"};
  if (!(std::isfinite(margin) && margin >= 0 && margin <= 1))
    return Error{"fem_contact: margin = " + formatNumber(margin) + ": must be in [0, 1]"};
  if (!(std::isfinite(max_depth) && max_depth > 0 && max_depth <= 0.5))
    return Error{"fem_contact: max_depth = " + formatNumber(max_depth) + ": must be in (0, 0.5]"};
  return Ok{};
}

// The candidate tests' rules for this pair: the search margin, the depth limit and the crease
// rule's depth (twice the gap tolerance, as self-contact's).
CandidateRules BodyPairContact::candidateRules(double margin) const {
  CandidateRules rules;
  rules.margin = margin;
  rules.max_depth = settings_.max_depth;
  rules.crease_depth = 2 * gap_tolerance_;
  return rules;
}

BodyPairContact::BodyPairContact(std::shared_ptr<const FemModel> a,
                                 std::shared_ptr<const FemModel> b,
                                 const BodyContactSettings& settings)
    : a_(std::move(a)),
      b_(std::move(b)),
      settings_(settings),
      node_count_a_(a_->nodeCount()),
      triangle_count_a_(static_cast<int>(a_->mesh().surfaceTriangles().size())),
      mean_edge_a_(meanSurfaceEdge(a_->mesh())),
      mean_edge_b_(meanSurfaceEdge(b_->mesh())),
      tree_a_(a_->mesh().surfaceTriangles()),
      tree_b_(b_->mesh().surfaceTriangles()),
      edges_a_(a_->mesh().surfaceTriangles()),
      edges_b_(b_->mesh().surfaceTriangles()) {
  gap_tolerance_ = settings_.gap_tolerance > 0 ? settings_.gap_tolerance
                                               : 1e-3 * std::min(mean_edge_a_, mean_edge_b_);
}

void BodyPairContact::replaceModels(std::shared_ptr<const FemModel> a,
                                    std::shared_ptr<const FemModel> b) {
  a_ = std::move(a);
  b_ = std::move(b);
}

bool BodyPairContact::detect(const Eigen::VectorXd& xa, const Eigen::VectorXd& va,
                             const Eigen::VectorXd& xb, const Eigen::VectorXd& vb, double dt) {
  set_.beginStep();
  start_a_ = xa;
  start_b_ = xb;
  end_a_ = xa + dt * va;
  end_b_ = xb + dt * vb;
  // a's nodes against b's triangles, then b's nodes against a's: a fixed order, so the candidates
  // (and the solve) are the same for any thread count.
  nodeNormals(a_->mesh(), xa, normals_a_);
  nodeNormals(b_->mesh(), xb, normals_b_);
  addCandidates(*a_, 0, xa, end_a_, normals_a_, tree_b_, node_count_a_, triangle_count_a_, xb,
                end_b_, settings_.margin * mean_edge_b_);
  // a's edges against b's, with b's tree still refitted to b's motion.
  if (settings_.edge_edge)
    addEdgeCandidates(xa, end_a_, xb, end_b_, settings_.margin * mean_edge_b_);
  addCandidates(*b_, node_count_a_, xb, end_b_, normals_b_, tree_a_, 0, 0, xa, end_a_,
                settings_.margin * mean_edge_a_);
  return !set_.empty();
}

void BodyPairContact::addCandidates(const FemModel& nodes_model, int node_offset,
                                    const Eigen::VectorXd& xn, const Eigen::VectorXd& en,
                                    const Eigen::VectorXd& node_normals, SurfaceTree& tree,
                                    int triangle_node_offset, int triangle_offset,
                                    const Eigen::VectorXd& xt, const Eigen::VectorXd& et,
                                    double margin) {
  tree.refit(xt, et, margin);
  const std::vector<Triangle>& triangles = tree.triangles();
  const CandidateRules rules = candidateRules(margin);
  auto at = [](const Eigen::VectorXd& positions, int node) -> Eigen::Vector3d {
    return positions.segment<3>(3 * node);
  };
  Eigen::Vector3d node_normal = Eigen::Vector3d::Zero();
  // Not facing the triangle while already touching its plane (resting or sliding along it, not
  // arriving): no contact, unless it held last step (no sudden release). A node still arriving is
  // paired whatever its normal: an edge or corner striking a face obliquely in a fast impact faces
  // it at any angle (filtered, two soft cubes at 15 m/s interpenetrated by 4 cm).
  const ExclusionRule not_facing = [&](const Eigen::Vector3d& normal, double gap) {
    return gap <= kFacingBand * gap_tolerance_ && node_normal.dot(normal) > -kFacing;
  };
  for (int p : nodes_model.mesh().surfaceNodes()) {
    const Eigen::Vector3d xp = xn.segment<3>(3 * p), ep = en.segment<3>(3 * p);
    node_normal = node_normals.segment<3>(3 * p);
    tree.query(xp.cwiseMin(ep), xp.cwiseMax(ep), found_);
    for (int t : found_) {
      const Triangle& tri = triangles[static_cast<size_t>(t)];
      const int pair_node = node_offset + p;
      const int pair_triangle = triangle_offset + t;
      // Behind the plane beyond the crease depth: only a contact held last step is still one (it
      // sank within its tolerance); a new pair there is a node past the other body's rim.
      const std::array<Eigen::Vector3d, 3> t0 = {at(xt, tri[0]), at(xt, tri[1]), at(xt, tri[2])};
      const std::optional<NodeTriangleHit> hit =
          nodeTriangleCandidate({xp, ep}, t0, {at(et, tri[0]), at(et, tri[1]), at(et, tri[2])},
                                rules, set_.wasActive(pair_node, pair_triangle), not_facing);
      if (!hit) continue;
      if (grazesRim(xp, t0, node_normal, hit->normal) && !set_.wasActive(pair_node, pair_triangle))
        continue;
      const Eigen::Vector3d& w = hit->weights;
      // The impulse's triangle point: the node's projection at the step's start, unclamped while
      // within the slack. Node and point then differ only along the normal, so the pair of
      // impulses has no moment about the start positions, where an implicit step's impulses act
      // on the angular momentum (clamping to the triangle gave levers: 1.5 % of the angular
      // momentum lost in bullet_collide_soft, 0.95 % without). A projection that enters the
      // triangle only later on the path takes the crossing's weights, clamped.
      const Eigen::Vector3d w_start =
          hit->when > 0 ? projectionWeights(xp, t0[0], t0[1], t0[2]) : w;
      const Eigen::Vector3d wc = w_start.allFinite() && w_start.minCoeff() >= -kFaceInsideTolerance
                                     ? w_start
                                     : Eigen::Vector3d(w.cwiseMax(0.0) / w.cwiseMax(0.0).sum());
      SurfaceContact c;
      c.nodes = {pair_node, triangle_node_offset + tri[0], triangle_node_offset + tri[1],
                 triangle_node_offset + tri[2]};
      c.beta = {1.0, -wc[0], -wc[1], -wc[2]};
      c.triangle = pair_triangle;
      c.normal = hit->normal;
      c.gap = hit->gap;
      c.target_gap = thickness();
      c.friction = settings_.friction;
      set_.add(c);
    }
  }
}

bool BodyPairContact::slidesAlongFlatFaces(const SurfaceContact& pair, const std::array<int, 2>& e,
                                           const std::array<int, 2>& f, const Eigen::VectorXd& xa,
                                           const Eigen::VectorXd& ea, const Eigen::VectorXd& xb,
                                           const Eigen::VectorXd& eb) const {
  const std::vector<Triangle>& triangles_a = tree_a_.triangles();
  const std::vector<Triangle>& triangles_b = tree_b_.triangles();
  if (edges_a_.foldCosine(pair.edge, triangles_a, xa) <= kFlatFold ||
      edges_b_.foldCosine(pair.triangle, triangles_b, xb) <= kFlatFold)
    return false;
  const Eigen::Vector3d na = edges_a_.outwardNormal(pair.edge, triangles_a, xa);
  const Eigen::Vector3d nb = edges_b_.outwardNormal(pair.triangle, triangles_b, xb);
  if (na.dot(nb) <= -kFacing) return false;  // faces meeting head-on
  // The step's relative motion of the two edges' midpoints, and whether it runs along a face.
  auto moved = [](const Eigen::VectorXd& start, const Eigen::VectorXd& end, int node) {
    return Eigen::Vector3d(end.segment<3>(3 * node) - start.segment<3>(3 * node));
  };
  const Eigen::Vector3d motion =
      0.5 * (moved(xb, eb, f[0]) + moved(xb, eb, f[1]) - moved(xa, ea, e[0]) - moved(xa, ea, e[1]));
  const double length = motion.norm();
  if (!(length > 0)) return false;
  return std::abs(motion.dot(na)) <= kFacing * length ||
         std::abs(motion.dot(nb)) <= kFacing * length;
}

void BodyPairContact::addEdgeCandidates(const Eigen::VectorXd& xa, const Eigen::VectorXd& ea,
                                        const Eigen::VectorXd& xb, const Eigen::VectorXd& eb,
                                        double margin) {
  const CandidateRules rules = candidateRules(margin);
  auto at = [](const Eigen::VectorXd& positions, int node) -> Eigen::Vector3d {
    return positions.segment<3>(3 * node);
  };
  // Each edge's box over the motion.
  auto box = [&](const std::array<int, 2>& e, const Eigen::VectorXd& x, const Eigen::VectorXd& end,
                 Eigen::Vector3d& lo, Eigen::Vector3d& hi) {
    lo = at(x, e[0]).cwiseMin(at(x, e[1])).cwiseMin(at(end, e[0])).cwiseMin(at(end, e[1]));
    hi = at(x, e[0]).cwiseMax(at(x, e[1])).cwiseMax(at(end, e[0])).cwiseMax(at(end, e[1]));
  };
  const std::vector<Triangle>& triangles_a = tree_a_.triangles();
  const std::vector<Triangle>& triangles_b = tree_b_.triangles();
  SurfaceContact contact;
  const std::function<const Eigen::Vector3d*()> held = [&] { return set_.warmStartOf(contact); };
  const std::function<Eigen::Vector3d()> outward = [&]() -> Eigen::Vector3d {
    return edges_b_.outwardNormal(contact.triangle, triangles_b, xb) -
           edges_a_.outwardNormal(contact.edge, triangles_a, xa);
  };
  // Where one of the edges lies on a flat part of its surface (its two triangles within 20
  // degrees of each other), only an arriving pair is new: two faces resting or sliding on each
  // other have edges crossing in one plane everywhere, which their node contacts hold already;
  // as edge pairs with friction they caught a soft block sliding down a soft slab (as nodes
  // ahead of its leading edge did, docs/contact.md, "Friction between FEM bodies"). Ridge
  // against ridge, which no node contact sees, is kept touching; a pair held last step stays.
  const ExclusionRule resting_on_flat = [&](const Eigen::Vector3d&, double gap) {
    return gap <= kFacingBand * gap_tolerance_ &&
           (edges_a_.foldCosine(contact.edge, triangles_a, xa) > kFlatFold ||
            edges_b_.foldCosine(contact.triangle, triangles_b, xb) > kFlatFold);
  };
  std::vector<int> later;
  for (size_t i = 0; i < edges_a_.edges.size(); ++i) {
    const std::array<int, 2>& e = edges_a_.edges[i];
    Eigen::Vector3d lo_e, hi_e;
    box(e, xa, ea, lo_e, hi_e);
    tree_b_.query(lo_e, hi_e, found_);
    // The edges of b's triangles found, each once, ascending.
    later.clear();
    for (int t : found_)
      for (int j : edges_b_.triangle_edges[static_cast<size_t>(t)])
        later.push_back(j);
    std::sort(later.begin(), later.end());
    later.erase(std::unique(later.begin(), later.end()), later.end());
    const std::array<std::array<Eigen::Vector3d, 2>, 2> edge_e = {
        {{at(xa, e[0]), at(xa, e[1])}, {at(ea, e[0]), at(ea, e[1])}}};
    contact.edge = static_cast<int>(i);
    for (int j : later) {
      const std::array<int, 2>& f = edges_b_.edges[static_cast<size_t>(j)];
      // Boxes over the motion more than the margin apart: never within it, never crossing.
      Eigen::Vector3d lo_f, hi_f;
      box(f, xb, eb, lo_f, hi_f);
      if (((lo_f.array() - margin) > hi_e.array()).any() ||
          ((hi_f.array() + margin) < lo_e.array()).any())
        continue;
      contact.triangle = j;
      const std::optional<EdgeEdgeHit> hit =
          edgeEdgeCandidate(edge_e, {{{at(xb, f[0]), at(xb, f[1])}, {at(eb, f[0]), at(eb, f[1])}}},
                            rules, held, outward, resting_on_flat);
      if (!hit) continue;
      if (held() == nullptr && slidesAlongFlatFaces(contact, e, f, xa, ea, xb, eb)) continue;
      SurfaceContact c = contact;
      c.nodes = {e[0], e[1], node_count_a_ + f[0], node_count_a_ + f[1]};
      c.beta = {1.0 - hit->u, hit->u, -(1.0 - hit->v), -hit->v};
      c.normal = hit->normal;
      c.gap = hit->gap;
      c.target_gap = thickness();
      c.friction = settings_.friction;
      set_.add(c);
    }
  }
}

int BodyPairContact::correctGaps(const Eigen::VectorXd& v, double dt, double tolerance) {
  auto end = [&](int node) -> Eigen::Vector3d {
    const Eigen::Vector3d x = node < node_count_a_
                                  ? start_a_.segment<3>(3 * node)
                                  : start_b_.segment<3>(3 * (node - node_count_a_));
    return x + dt * v.segment<3>(3 * node);
  };
  int shifted = 0;
  for (SurfaceContact& c : set_.contacts()) {
    if (c.determined || c.edge >= 0) continue;
    const Eigen::Vector3d p = end(c.nodes[0]), a = end(c.nodes[1]), b = end(c.nodes[2]),
                          t = end(c.nodes[3]);
    Eigen::Vector3d n = (b - a).cross(t - a);
    if (!(n.norm() > 0)) continue;
    n.normalize();
    const double true_gap = n.dot(p - a);
    if (true_gap >= c.target_gap - tolerance) continue;  // within the tolerance of its target
    const Eigen::Vector3d w = projectionWeights(p, a, b, t);
    if (!w.allFinite() || w.minCoeff() < -kFaceInsideTolerance)
      continue;  // slid off: not this face
    Eigen::Vector3d u = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < 4; ++k)
      u += c.beta[k] * v.segment<3>(3 * c.nodes[k]);
    const double linear_gap = c.gap + dt * c.normal.dot(u);
    if (true_gap < linear_gap) {
      c.gap += true_gap - linear_gap;
      ++shifted;
    }
  }
  return shifted;
}

}  // namespace torsion
