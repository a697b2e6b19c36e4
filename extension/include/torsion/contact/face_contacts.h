#pragma once
// Face contacts (docs/contact-pipeline.md, "Face contacts"): a rigid shape against the inside of an
// FEM surface triangle or edge. Node contacts hold a rigid surface only at nodes; a rigid corner,
// an edge or a sphere smaller than the mesh spacing would sink between them. A face contact holds
// the face's point nearest the shape (barycentric weights w on its nodes) against the rigid point
// nearest it. Touched only by the simulation thread.
//
// Relative velocity u = sum_j w_j v_j - J V (J V the rigid point's velocity) and the end-of-step
// gap gap + dt n.u. Each contact is a row of the body's contact island
// (contact/solve/face_contact_rows.h).

#include <BulletCollision/CollisionShapes/btCollisionShape.h>

#include <Eigen/Core>
#include <array>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "torsion/contact/rigid_partner.h"
#include "torsion/mesh/tet_mesh.h"
#include "torsion/solve/fem_state.h"
#include "torsion/solve/node_constraints.h"

namespace torsion {

struct FaceContact {
  enum class State { kInactive, kSlide, kStick };
  std::array<int, 3> nodes{};                         ///< the surface triangle's nodes
  Eigen::Vector3d weights = Eigen::Vector3d::Zero();  ///< barycentric; an edge contact has a 0
  /// The nodes of non-zero weight, sorted, -1 padded: the contact's identity across steps (an
  /// edge contact found from both of its triangles is one contact).
  std::array<int, 3> key{};
  int partner = -1;                                   ///< index into the solver's partners
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit, from the rigid surface to the face
  double gap = 0;                                     ///< m, signed, at the start of the step
  Eigen::Vector3d lever = Eigen::Vector3d::Zero();    ///< m, rigid point minus centre of mass
  double friction = 0;                                ///< pair coefficient
  State state = State::kInactive;                     ///< after the solve
  Eigen::Vector3d impulse = Eigen::Vector3d::Zero();  ///< N s the rigid body gave the face
};

class FaceContactSet {
 public:
  explicit FaceContactSet(const TetMesh& mesh);

  /// Forgets last step's contacts.
  void beginStep();
  /// The longest surface edge now: a triangle overlapping a box has its nodes within this of it.
  double longestEdge(const FemState& state) const;
  /// Narrow phase against one rigid object whose (start-of-step) bounds are [lo, hi]: the surface
  /// triangles of `nearby_nodes` (every node within reach + longestEdge() of the bounds) whose
  /// bounds come within `reach` get the shape's distance (face_distance.h); a point at a
  /// triangle's corner is left to the node contact; a face all of whose nodes are held is left
  /// out unless the partner is dynamic (held nodes push, never yield); a face that the predicted
  /// motion over `dt` (s) would rather hold against the shape's supporting plane facing it (a
  /// triangle just ahead of a sliding box's edge) is left to its nodes (`dt`: the solve's
  /// look-ahead, RigidContactSolver::lookahead). A triangle with a node in `glued` (per node,
  /// non-zero: anchored to this object; empty: none) is left out: where a body is glued to the
  /// object, the two are one, not in contact (at a large step the object's own corners, within
  /// reach of the glued face's neighbours, read as deep penetrations and fought the anchors).
  void detect(const FemState& state, const NodeConstraints& held,
              const std::vector<int>& nearby_nodes, const btCollisionShape& shape,
              const btTransform& transform, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
              double reach, double dt, int partner, const RigidPartner& p, double friction,
              const std::vector<char>& glued);
  const std::vector<FaceContact>& contacts() const { return contacts_; }
  /// The contacts of polyhedral shapes' corners and edges (query/feature_contacts.h) found by
  /// this step's detect(); contacts() holds the other shapes' nearest points.
  const std::vector<FaceContact>& featureContacts() const { return features_; }
  /// No contact of either kind this step.
  bool empty() const { return contacts_.empty() && features_.empty(); }

  /// The surface triangles of `node` (indices into the mesh's surfaceTriangles()): [first, last).
  std::pair<const int*, const int*> trianglesOf(int node) const {
    const auto n = static_cast<std::size_t>(node);
    return {node_triangles_.data() + node_triangle_start_[n],
            node_triangles_.data() + node_triangle_start_[n + 1]};
  }

 private:
  // The face contact of triangle `tri` (its corners at `state`) with the shape, if it is one
  // (within reach, not at a corner, nearer than its nodes, not better held by its nodes against
  // the supporting plane).
  std::optional<FaceContact> faceContact(const FemState& state, const Triangle& tri,
                                         const btCollisionShape& shape,
                                         const btTransform& transform, double reach, double dt,
                                         int partner, const RigidPartner& p, double friction) const;
  // Adds `fc`, or keeps the nearer reading of an edge two triangles found.
  void add(const FaceContact& fc);

  std::vector<Triangle> triangles_;
  std::vector<int> node_triangle_start_, node_triangles_;  // CSR: surface triangles by node
  std::vector<int> triangle_stamp_;                        // per triangle: last detect seen
  int stamp_ = 0;
  std::vector<FaceContact> contacts_;
  std::vector<FaceContact> features_;
  std::map<std::pair<std::array<int, 3>, int>, int> index_;  // (key, partner) -> contact
};

}  // namespace torsion
