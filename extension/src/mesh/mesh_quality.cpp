#include "torsion/mesh/mesh_quality.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace torsion {

std::array<double, 6> dihedralAngles(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                     const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  // Outward normals of the faces opposite a, b, c, d (orientation-independent: each normal is
  // flipped to point away from the vertex it is opposite to).
  const std::array<Eigen::Vector3d, 4> x = {a, b, c, d};
  std::array<Eigen::Vector3d, 4> normal;
  for (size_t i = 0; i < 4; ++i) {
    const Eigen::Vector3d& p = x[(i + 1) % 4];
    const Eigen::Vector3d& q = x[(i + 2) % 4];
    const Eigen::Vector3d& r = x[(i + 3) % 4];
    Eigen::Vector3d n = (q - p).cross(r - p);
    if (n.dot(x[i] - p) > 0) n = -n;
    normal[i] = n.normalized();
  }
  // The edge (i, j) lies on the two faces opposite the other two vertices k, l; the interior
  // angle there is pi minus the angle between those faces' outward normals.
  constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  std::array<double, 6> angles{};
  for (size_t e = 0; e < 6; ++e) {
    int others[2], m = 0;
    for (int v = 0; v < 4; ++v) {
      if (v != kEdges[e][0] && v != kEdges[e][1]) others[m++] = v;
    }
    const double cosine = std::clamp(
        normal[static_cast<size_t>(others[0])].dot(normal[static_cast<size_t>(others[1])]), -1.0,
        1.0);
    angles[e] = M_PI - std::acos(cosine);
  }
  return angles;
}

MeshQuality measureQuality(const TetMesh& mesh, const std::vector<Eigen::Vector3d>& positions) {
  MeshQuality q;
  q.min_dihedral_deg = std::numeric_limits<double>::infinity();
  q.max_dihedral_deg = 0;
  double aspect_sum = 0;
  for (const Tet& tet : mesh.tets()) {
    const Eigen::Vector3d& a = positions[static_cast<size_t>(tet[0])];
    const Eigen::Vector3d& b = positions[static_cast<size_t>(tet[1])];
    const Eigen::Vector3d& c = positions[static_cast<size_t>(tet[2])];
    const Eigen::Vector3d& d = positions[static_cast<size_t>(tet[3])];
    const double six_volume = sixSignedVolume(a, b, c, d);
    if (six_volume <= 0) ++q.inverted_tets;

    for (double angle : dihedralAngles(a, b, c, d)) {
      q.min_dihedral_deg = std::min(q.min_dihedral_deg, angle * 180.0 / M_PI);
      q.max_dihedral_deg = std::max(q.max_dihedral_deg, angle * 180.0 / M_PI);
    }

    const double longest = std::max({(a - b).norm(), (a - c).norm(), (a - d).norm(), (b - c).norm(),
                                     (b - d).norm(), (c - d).norm()});
    const double area = 0.5 * ((b - a).cross(c - a).norm() + (b - a).cross(d - a).norm() +
                               (c - a).cross(d - a).norm() + (c - b).cross(d - b).norm());
    const double inradius = 0.5 * std::abs(six_volume) / area;  // 3 V / A
    const double aspect = inradius > 0 ? longest / (2.0 * std::sqrt(6.0) * inradius)
                                       : std::numeric_limits<double>::infinity();
    q.max_aspect_ratio = std::max(q.max_aspect_ratio, aspect);
    aspect_sum += aspect;
  }
  q.mean_aspect_ratio = mesh.tetCount() > 0 ? aspect_sum / mesh.tetCount() : 0;
  if (mesh.tetCount() == 0) q.min_dihedral_deg = 0;
  return q;
}

}  // namespace torsion
