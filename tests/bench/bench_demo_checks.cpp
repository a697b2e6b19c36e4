#include "bench_demo_checks.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace torsion::bench {

namespace {

Eigen::Vector3d centroid(const std::vector<Eigen::Vector3d>& nodes) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : nodes)
    c += p;
  return nodes.empty() ? c : Eigen::Vector3d(c / static_cast<double>(nodes.size()));
}

double lowestZ(const std::vector<Eigen::Vector3d>& nodes) {
  double z = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& p : nodes)
    z = std::min(z, p.z());
  return z;
}

double highestZ(const std::vector<Eigen::Vector3d>& nodes) {
  double z = -std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& p : nodes)
    z = std::max(z, p.z());
  return z;
}

// Tets whose signed volume at the end is not positive (the rest meshes are oriented positive).
int invertedTets(const TetMesh& rest, const std::vector<Eigen::Vector3d>& x) {
  int inverted = 0;
  for (const Tet& t : rest.tets()) {
    const Eigen::Vector3d& a = x[static_cast<size_t>(t[0])];
    const double v =
        (x[static_cast<size_t>(t[1])] - a)
            .dot((x[static_cast<size_t>(t[2])] - a).cross(x[static_cast<size_t>(t[3])] - a));
    if (!(v > 0)) ++inverted;
  }
  return inverted;
}

// RMS distance between x and the rest shape moved rigidly onto it (Kabsch's best fit): how far
// the body is from its rest shape, whatever its pose.
double shapeError(const TetMesh& rest, const std::vector<Eigen::Vector3d>& x) {
  const std::vector<Eigen::Vector3d>& r = rest.restPositions();
  const Eigen::Vector3d rc = centroid(r), xc = centroid(x);
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < r.size(); ++i)
    h += (r[i] - rc) * (x[i] - xc).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
  const Eigen::Matrix3d rotation = svd.matrixV() * d * svd.matrixU().transpose();
  double sum = 0;
  for (size_t i = 0; i < r.size(); ++i)
    sum += (rotation * (r[i] - rc) + xc - x[i]).squaredNorm();
  return std::sqrt(sum / static_cast<double>(r.size()));
}

// How deep p lies inside the box (> 0 inside), or -inf for other shapes.
double depthInBox(const scene::RigidBodySpec& r, const Frame& pose, const Eigen::Vector3d& p) {
  if (r.shape != scene::RigidBodySpec::Shape::kBox) return -std::numeric_limits<double>::infinity();
  const Eigen::Vector3d local = pose.toLocal(p);
  return (r.half_extents - local.cwiseAbs()).minCoeff();
}

int rigidIndex(const scene::SceneSpec& spec, const std::string& name) {
  for (size_t i = 0; i < spec.rigid_bodies.size(); ++i)
    if (spec.rigid_bodies[i].name == name) return static_cast<int>(i);
  return -1;
}

}  // namespace

Verdict judge(const scene::SceneSpec& spec, const std::vector<TetMesh>& rest, const EndState& end,
              int steps, double tolerance) {
  Verdict v;
  std::ostringstream d;
  v.exploded = !end.finite || end.max_node_speed > spec.world.solver.max_speed;
  if (!end.finite || end.nodes.size() != rest.size() ||
      end.rigid.size() != spec.rigid_bodies.size()) {
    v.outcome = "failed";
    v.detail = !end.finite ? "non-finite state" : "incomplete end state";
    return v;
  }
  int inverted = 0;
  for (size_t b = 0; b < rest.size(); ++b)
    inverted += invertedTets(rest[b], end.nodes[b]);
  d << "inverted tets " << inverted << "; ";
  if (spec.ground) {
    const double ground = spec.ground->plane_offset;
    for (const auto& nodes : end.nodes)
      v.sank = v.sank || lowestZ(nodes) < ground - tolerance;
    for (size_t r = 0; r < spec.rigid_bodies.size(); ++r) {
      const scene::RigidBodySpec& rb = spec.rigid_bodies[r];
      if (rb.mass <= 0 || rb.shape != scene::RigidBodySpec::Shape::kBox) continue;
      for (int corner = 0; corner < 8; ++corner) {
        const Eigen::Vector3d local(corner & 1 ? rb.half_extents.x() : -rb.half_extents.x(),
                                    corner & 2 ? rb.half_extents.y() : -rb.half_extents.y(),
                                    corner & 4 ? rb.half_extents.z() : -rb.half_extents.z());
        v.sank = v.sank || end.rigid[r].toWorld(local).z() < ground - tolerance;
      }
    }
  }
  double deepest = 0;
  for (size_t r = 0; r < spec.rigid_bodies.size(); ++r)
    for (const auto& nodes : end.nodes)
      for (const Eigen::Vector3d& p : nodes)
        deepest = std::max(deepest, depthInBox(spec.rigid_bodies[r], end.rigid[r], p));
  v.passed_through = deepest > tolerance;
  d << "deepest node in a box " << deepest << " m; ";

  // The defining outcome of each re-created demo (docs/performance-contact.md).
  const std::vector<Eigen::Vector3d>& cube = end.nodes.front();  // the demo's one soft body
  const Eigen::Vector3d c = centroid(cube);
  d << "soft body centroid (" << c.x() << ", " << c.y() << ", " << c.z() << "), z " << lowestZ(cube)
    << " to " << highestZ(cube);
  bool ok = true;
  if (spec.name == "bullet_pinch") {
    // Lifted: the cube started with its bottom at 2 m and the fingers rise 8 m; held: its centre
    // stays between the fingers.
    const Frame& left = end.rigid[static_cast<size_t>(rigidIndex(spec, "finger_left"))];
    const Frame& right = end.rigid[static_cast<size_t>(rigidIndex(spec, "finger_right"))];
    const Eigen::Vector3d mid = (left.origin + right.origin) / 2;
    ok = lowestZ(cube) > 4 && std::abs(c.z() - mid.z()) < 1.5 && std::abs(c.y() - mid.y()) < 1;
  } else if (spec.name == "bullet_collide") {
    // The box hit the cube and stayed below it, and momentum held: box (0.5 kg, 30 m/s up) and
    // cube (0.5 kg, at rest) have their centre of mass moving at 15 m/s from (7 - 2) / 2 = 2.5 m.
    // The node mean stands for the cube's centre of mass (lumped masses of a regular mesh; the
    // 0.75 m allowance, 5 % of the 15 m travelled, covers the difference).
    const Frame& box = end.rigid[static_cast<size_t>(rigidIndex(spec, "box"))];
    const double travelled = (box.origin.z() + c.z()) / 2 - 2.5;
    const double expected = 15 * spec.world.solver.time_step * static_cast<double>(steps);
    ok = box.origin.z() + 2 < c.z() && std::abs(travelled - expected) < 0.05 * expected;
    d << "; box z " << box.origin.z() << "; centre of mass moved " << travelled
      << " m (momentum: " << expected << ")";
  } else if (spec.name == "bullet_collide_moving") {
    // The same pair thrown at each other at 15 m/s each: no momentum, so the centre of mass of
    // box + cube (equal masses) stays at (7 - 2) / 2 = 2.5 m; 0.75 m allowed as above (5 % of
    // the 15 m each body would travel), and the box stays below the cube.
    const Frame& box = end.rigid[static_cast<size_t>(rigidIndex(spec, "box"))];
    const double travelled = (box.origin.z() + c.z()) / 2 - 2.5;
    ok = box.origin.z() + 2 < c.z() && std::abs(travelled) < 0.75;
    d << "; box z " << box.origin.z() << "; centre of mass moved " << travelled
      << " m (momentum: 0)";
  } else if (spec.name == "bullet_volumetric_deformable") {
    // The cube came to rest on the ground inside the four walls, under the boxes that fell on it.
    ok = lowestZ(cube) > -tolerance && c.z() > 1 && c.z() < 3;
    for (const Eigen::Vector3d& p : cube)
      ok = ok && std::abs(p.x()) < 4 + tolerance && std::abs(p.y()) < 4 + tolerance;
  } else if (spec.name == "bullet_large_deformation") {
    // Squeezed to 30 % of its height, released: back near its rest shape (RMS off the best
    // rigid fit below 5 % of the 4 m edge, whatever it turned), nothing inverted, and where it
    // was squeezed (the plates leave symmetrically).
    const double error = shapeError(rest.front(), cube);
    ok = error < 0.2 && inverted == 0 && std::abs(c.z() - 8) < 1;
    d << "; off its rest shape by " << error << " m RMS";
  } else if (spec.name == "bullet_deformable_rigid") {
    // The five boxes (2 m) stay stacked on the sheet held at its corners: four on the sheet
    // (top at 0.1 m; centres at 1.1 m less its sag), the fifth on them.
    const std::vector<Eigen::Vector3d>& sheet = end.nodes.front();
    ok = inverted == 0;
    for (size_t r = 0; r < end.rigid.size(); ++r) {
      const double z = end.rigid[r].origin.z();
      ok = ok && (r < 4 ? z > 0.8 && z < 1.3 : z > 2.8 && z < 3.4);
      d << "; " << spec.rigid_bodies[r].name << " z " << z;
    }
    d << "; sheet z " << lowestZ(sheet) << " to " << highestZ(sheet);
  } else {
    v.detail = d.str();
    return v;
  }
  v.outcome = ok ? "ok" : "failed";
  v.detail = d.str();
  return v;
}

}  // namespace torsion::bench
