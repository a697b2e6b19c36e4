#include "torsion/contact/face_contacts.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "torsion/contact/face_distance.h"
#include "torsion/contact/query/feature_contacts.h"
#include "torsion/contact/shape_distance.h"

namespace torsion {

namespace {

// A weight below this puts the contact point on the opposite edge (or corner): the contact is the
// edge's (or the node's), whichever triangle found it.
constexpr double kEdgeWeight = 1e-6;
// A face point must come this fraction of the detection reach nearer the shape than its nodes'
// interpolated distances to be a contact of its own (round-off on flat-on-flat is far below).
constexpr double kDuplicateMargin = 1e-3;
// m: round-off between the nearest pair's and a supporting plane's predicted end gaps.
constexpr double kPlaneChoiceMargin = 1e-9;

// Whether the triangle is better held against the rigid shape's supporting plane that faces it
// (normal minus the triangle's) than along the nearest pair (f), by the end gaps the predicted
// motion leaves (the nodes' velocities, the rigid body's after Bullet's integration). A triangle
// on a flat surface just ahead of a sliding box is nearest the box's front face, and the end gap
// along that horizontal normal stops the box as at a wall; the box's bottom edge will pass over
// the triangle, whose nodes hold it against the bottom plane themselves (node contacts take the
// same plane, rigid_contact.cpp), so such a face contact is left out. At rest the nearest pair
// is never farther than a supporting plane: nothing changes.
bool supportPlaneLeavesMore(const btCollisionShape& shape, const btTransform& transform,
                            const FemState& state, const Triangle& tri, const FacePoint& f,
                            const RigidPartner& p, double dt) {
  const Eigen::Vector3d a = state.position(tri[0]), b = state.position(tri[1]),
                        c = state.position(tri[2]);
  const Eigen::Vector3d outward = (b - a).cross(c - a);
  if (outward.squaredNorm() == 0) return false;
  const Eigen::Vector3d rigid = pointVelocity(p.entry_velocity, f.shape_point - p.com);
  Eigen::Vector3d face_velocity = Eigen::Vector3d::Zero();
  for (size_t j = 0; j < 3; ++j)
    face_velocity += f.barycentric[static_cast<Eigen::Index>(j)] * state.velocity(tri[j]);
  const Eigen::Vector3d into = -outward.normalized();
  // Only the motion along the plane predicts which side the face ends on: across it, the rigid
  // body's predicted velocity carries the step's gravity, which the contacts under it cancel.
  Eigen::Vector3d slip = face_velocity - rigid;
  slip -= into * into.dot(slip);
  const double end_nearest = f.distance + dt * f.normal.dot(slip);
  double end_plane = std::numeric_limits<double>::infinity();
  for (size_t j = 0; j < 3; ++j) {
    const std::optional<SurfacePoint> plane =
        supportPlaneDistance(shape, transform, state.position(tri[j]), into);
    if (!plane) return false;
    end_plane = std::min(end_plane, plane->distance);
  }
  return end_plane > end_nearest + kPlaneChoiceMargin;
}

}  // namespace

FaceContactSet::FaceContactSet(const TetMesh& mesh) : triangles_(mesh.surfaceTriangles()) {
  const int n = mesh.nodeCount();
  node_triangle_start_.assign(static_cast<size_t>(n) + 1, 0);
  for (const Triangle& t : triangles_) {
    for (int node : t)
      ++node_triangle_start_[static_cast<size_t>(node) + 1];
  }
  for (int i = 0; i < n; ++i)
    node_triangle_start_[static_cast<size_t>(i) + 1] +=
        node_triangle_start_[static_cast<size_t>(i)];
  node_triangles_.resize(static_cast<size_t>(node_triangle_start_.back()));
  std::vector<int> fill(node_triangle_start_.begin(), node_triangle_start_.end() - 1);
  for (size_t t = 0; t < triangles_.size(); ++t) {
    for (int node : triangles_[t])
      node_triangles_[static_cast<size_t>(fill[static_cast<size_t>(node)]++)] = static_cast<int>(t);
  }
  triangle_stamp_.assign(triangles_.size(), 0);
}

void FaceContactSet::beginStep() {
  contacts_.clear();
  features_.clear();
  index_.clear();
}

double FaceContactSet::longestEdge(const FemState& state) const {
  double longest = 0;
  for (const Triangle& t : triangles_) {
    for (size_t k = 0; k < 3; ++k) {
      longest = std::max(longest, (state.position(t[k]) - state.position(t[(k + 1) % 3])).norm());
    }
  }
  return longest;
}

void FaceContactSet::detect(const FemState& state, const NodeConstraints& held,
                            const std::vector<int>& nearby_nodes, const btCollisionShape& shape,
                            const btTransform& transform, const Eigen::Vector3d& lo,
                            const Eigen::Vector3d& hi, double reach, double dt, int partner,
                            const RigidPartner& p, double friction,
                            const std::vector<char>& glued) {
  ++stamp_;
  const Eigen::Vector3d pad = Eigen::Vector3d::Constant(reach);
  const std::optional<PolyhedronFeatures> polyhedron = polyhedronFeatures(shape, transform);
  std::optional<FeatureContactCollector> features;
  if (polyhedron && !p.supported) features.emplace(*polyhedron, reach, partner, p, friction);
  for (int node : nearby_nodes) {
    for (int k = node_triangle_start_[static_cast<size_t>(node)];
         k < node_triangle_start_[static_cast<size_t>(node) + 1]; ++k) {
      const int t = node_triangles_[static_cast<size_t>(k)];
      if (triangle_stamp_[static_cast<size_t>(t)] == stamp_) continue;
      triangle_stamp_[static_cast<size_t>(t)] = stamp_;
      const Triangle& tri = triangles_[static_cast<size_t>(t)];
      const Eigen::Vector3d a = state.position(tri[0]), b = state.position(tri[1]),
                            c = state.position(tri[2]);
      const Eigen::Vector3d tlo = a.cwiseMin(b).cwiseMin(c), thi = a.cwiseMax(b).cwiseMax(c);
      if ((tlo.array() > (hi + pad).array()).any() || (thi.array() < (lo - pad).array()).any())
        continue;
      bool all_held = true, on_glue = false;
      for (int node_id : tri) {
        all_held = all_held && held.kind(node_id) == NodeConstraints::Kind::kFull;
        on_glue = on_glue || (!glued.empty() && glued[static_cast<size_t>(node_id)] != 0);
      }
      if (on_glue) continue;
      if (all_held && !p.dynamic) continue;
      if (features) features->addTriangle(tri, a, b, c);
      // A supported partner (resting on the ground: coupled explicitly, one step late) gets node
      // contacts only. Face contacts at its edges, with their levers and oblique normals, spun a
      // box squeezed under a deformable faster each step through that explicit coupling (its
      // rotation is resolved against the ground by Bullet only the step after).
      if (p.supported) continue;
      std::optional<FaceContact> fc =
          faceContact(state, tri, shape, transform, reach, dt, partner, p, friction);
      if (fc) add(*fc);
    }
  }
  if (features) features->appendTo(features_);
}

std::optional<FaceContact> FaceContactSet::faceContact(const FemState& state, const Triangle& tri,
                                                       const btCollisionShape& shape,
                                                       const btTransform& transform, double reach,
                                                       double dt, int partner,
                                                       const RigidPartner& p,
                                                       double friction) const {
  const Eigen::Vector3d a = state.position(tri[0]), b = state.position(tri[1]),
                        c = state.position(tri[2]);
  const std::optional<FacePoint> f = shapeToTriangle(shape, transform, a, b, c, reach);
  if (!f || f->distance > reach) return std::nullopt;
  // At a corner: the node's own contact measures the same distance.
  if (f->barycentric.maxCoeff() > 1 - kEdgeWeight) return std::nullopt;
  // A face point no nearer the shape than its nodes' own distances, interpolated, is held by
  // the node contacts (a flat rigid face on a flat soft face): a face contact there would only
  // duplicate them. What is left are rigid features that come nearer between the nodes than at
  // them: corners, edges, curved shapes.
  double interpolated = 0;
  for (size_t j = 0; j < 3; ++j) {
    const std::optional<SurfacePoint> d =
        signedDistance(shape, transform, state.position(tri[j]), reach);
    interpolated += f->barycentric[static_cast<Eigen::Index>(j)] *
                    (d ? d->distance : std::numeric_limits<double>::infinity());
  }
  if (f->distance >= interpolated - kDuplicateMargin * reach) return std::nullopt;
  if (supportPlaneLeavesMore(shape, transform, state, tri, *f, p, dt)) return std::nullopt;
  FaceContact fc;
  fc.nodes = {tri[0], tri[1], tri[2]};
  fc.weights = f->barycentric;
  // Sorted nodes of non-zero weight, -1 padded (no per-triangle allocation: a hot loop).
  fc.key = {-1, -1, -1};
  size_t used = 0;
  for (size_t j = 0; j < 3; ++j) {
    if (fc.weights[static_cast<Eigen::Index>(j)] > kEdgeWeight) fc.key[used++] = tri[j];
  }
  std::sort(fc.key.begin(), fc.key.begin() + static_cast<std::ptrdiff_t>(used));
  fc.partner = partner;
  fc.normal = f->normal;
  fc.gap = f->distance;
  fc.lever = f->shape_point - p.com;
  fc.friction = friction;
  return fc;
}

void FaceContactSet::add(const FaceContact& fc) {
  const auto found = index_.find({fc.key, fc.partner});
  if (found != index_.end()) {
    // An edge seen from its two triangles: keep the nearer reading.
    FaceContact& existing = contacts_[static_cast<size_t>(found->second)];
    if (fc.gap < existing.gap) existing = fc;
    return;
  }
  index_[{fc.key, fc.partner}] = static_cast<int>(contacts_.size());
  contacts_.push_back(fc);
}

}  // namespace torsion
