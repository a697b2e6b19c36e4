#pragma once
// Contacts of a polyhedral rigid shape's features with an FEM surface (docs/contact-solve.md,
// "From detection to rows"). Node contacts sample the surface at its nodes; these sample the
// shape where nodes cannot: its corners over the inside of a triangle, and its edges where they
// cross an edge of the surface. Together the two sample every pair of features that can touch
// (vertex-face both ways, edge-edge), each at a point fixed on its feature, so a box resting
// flat on a soft slab gets the same points step after step. The nearest point of a shape to a
// triangle (face_distance.h) is not a feature: where a box's face or edge lies flat on a
// triangle, every point of the overlap is nearest, and the one GJK returns jumps between its
// ends from one step to the next.
//
//   corner over a triangle   the corner's projection inside the triangle (barycentric weights;
//                            one within 1e-3 of a node is that node's contact), the triangle's
//                            inward normal, the corner's height above its plane
//   edge across an edge      the closest points of the two segments, both inside their segments,
//                            the common normal oriented from the shape to the surface, their
//                            distance along it; only where that normal lies in both edges' normal
//                            cones (between the outward normals of the shape's two faces at its
//                            edge, and of the surface's two triangles at its edge, within 0.2 rad):
//                            a box's vertical edge never meets a flat surface's edge as a wall,
//                            while its bottom edge lying on the surface meets every edge it crosses
//
// Boxes are taken sharp, with their margin (the surface node distances measure, shape_distance.h);
// a convex hull's points are inflated by its margin, as GJK measures it.
// Touched only by the simulation thread.

#include <BulletCollision/CollisionShapes/btCollisionShape.h>
#include <LinearMath/btTransform.h>

#include <Eigen/Core>
#include <array>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "torsion/contact/face_contacts.h"
#include "torsion/contact/rigid_partner.h"
#include "torsion/mesh/tet_mesh.h"

namespace torsion {

/// A polyhedral shape's corners and edges, world frame, at one pose.
struct PolyhedronFeatures {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 2>> edges;  ///< indices into vertices
  /// Per edge, the outward unit normals of the two faces that meet at it.
  std::vector<std::array<Eigen::Vector3d, 2>> edge_faces;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double margin = 0;  ///< m, the rounding that inflates the vertices (0 for a box)
};

/// Whether polyhedronFeatures gives `shape`'s features (a box or a convex hull).
bool hasPolyhedronFeatures(const btCollisionShape& shape);

/// The features of a box (btBoxShape) or convex hull (btConvexHullShape, its hull's edges from
/// Bullet's btConvexHullComputer) at `transform`; nullopt for every other shape.
std::optional<PolyhedronFeatures> polyhedronFeatures(const btCollisionShape& shape,
                                                     const btTransform& transform);

/// The feature contacts of one shape with the triangles of an FEM surface, each corner and each
/// pair of crossing edges once however many triangles find it.
class FeatureContactCollector {
 public:
  /// `reach` (m): contacts with a gap in [-reach, reach] are kept; `partner` and `friction` are
  /// copied into each contact, levers measured from `p.com`.
  FeatureContactCollector(const PolyhedronFeatures& features, double reach, int partner,
                          const RigidPartner& p, double friction)
      : features_(features),
        reach_(reach),
        partner_(partner),
        partner_data_(p),
        friction_(friction) {}

  /// The contacts of the features with triangle `tri` at positions (a, b, c), counter-clockwise
  /// seen from outside the body.
  void addTriangle(const Triangle& tri, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                   const Eigen::Vector3d& c);
  /// Appends the contacts found to `out`, corners first, then edge crossings, each group in
  /// feature order.
  void appendTo(std::vector<FaceContact>& out) const;

 private:
  /// A surface edge seen from its triangles (one or both of them).
  struct SurfaceEdge {
    Eigen::Vector3d from, to;
    std::vector<Eigen::Vector3d> outward;  ///< its triangles' outward unit normals
  };
  void addCorner(int vertex, const Triangle& tri, const std::array<Eigen::Vector3d, 3>& x,
                 const Eigen::Vector3d& outward);
  void addEdgeCrossing(int edge, const std::pair<int, int>& nodes, const SurfaceEdge& surface,
                       std::vector<FaceContact>& out) const;
  FaceContact contactAt(const Eigen::Vector3d& shape_point, const Eigen::Vector3d& normal,
                        double gap) const;

  const PolyhedronFeatures& features_;
  double reach_;
  int partner_;
  const RigidPartner& partner_data_;
  double friction_;
  std::map<int, FaceContact> corners_;  // by vertex: the triangle it is highest above
  std::map<std::pair<int, int>, SurfaceEdge> surface_edges_;  // by (smaller node, larger node)
};

}  // namespace torsion
