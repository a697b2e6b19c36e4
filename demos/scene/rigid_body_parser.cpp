#include "rigid_body_parser.h"

#include <algorithm>
#include <cmath>

#include "arithmetic_bounds.h"
#include "device_parser.h"
#include "torsion/format_number.h"

namespace torsion::scene {

namespace {

// A rigid length the arithmetic can carry (arithmetic_bounds.h).
double readLength(const JsonObject& s, const std::string& key) {
  const double value = s.number(key);
  if (!(value > 0)) s.fail(key, "must be > 0");
  if (value > kMaxRigidLength)
    s.fail(key, "must be at most 1e6 m (Bullet's inertias grow as size^2 and must stay finite)");
  return value;
}

void checkPoints(const JsonObject& s, const std::string& key,
                 const std::vector<Eigen::Vector3d>& points) {
  for (size_t i = 0; i < points.size(); ++i) {
    if (points[i].cwiseAbs().maxCoeff() > kMaxRigidLength)
      s.fail(key, "element " + std::to_string(i) + ": coordinates must be within 1e6 m");
  }
}

void readShape(const JsonObject& shape, RigidBodySpec& spec) {
  const std::string kind =
      shape.oneOf({"box", "sphere", "capsule", "convex_hull", "plane", "triangle_mesh"});
  const JsonObject s = shape.object(kind);
  if (kind == "box") {
    spec.shape = RigidBodySpec::Shape::kBox;
    spec.half_extents = s.vector3("half_extents");
    if (!(spec.half_extents.minCoeff() > 0)) s.fail("half_extents", "must be > 0");
    if (spec.half_extents.maxCoeff() > kMaxRigidLength)
      s.fail("half_extents", "must be at most 1e6 m (Bullet's inertias must stay finite)");
  } else if (kind == "sphere") {
    spec.shape = RigidBodySpec::Shape::kSphere;
    spec.radius = readLength(s, "radius");
  } else if (kind == "capsule") {
    spec.shape = RigidBodySpec::Shape::kCapsule;
    spec.radius = readLength(s, "radius");
    spec.half_height = readLength(s, "half_height");
    const std::string axis = s.string("axis", "z");
    if (axis != "x" && axis != "y" && axis != "z")
      s.fail("axis", "'" + axis + "' is not one of: x, y, z");
    spec.axis = axis[0] - 'x';
  } else if (kind == "convex_hull") {
    spec.shape = RigidBodySpec::Shape::kConvexHull;
    spec.points = s.vector3List("points");
    if (spec.points.size() < 4) s.fail("points", "a convex hull needs at least 4 points");
    checkPoints(s, "points", spec.points);
    // Not flat: some point off the plane of the first three (or of any line, if collinear).
    Eigen::Vector3d extent = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& p : spec.points)
      extent = extent.cwiseMax((p - spec.points[0]).cwiseAbs());
    double volume = 0;
    for (size_t a = 1; a < spec.points.size(); ++a) {
      for (size_t b = a + 1; b < spec.points.size(); ++b) {
        for (size_t c = b + 1; c < spec.points.size(); ++c) {
          volume = std::max(volume, std::abs((spec.points[a] - spec.points[0])
                                                 .cross(spec.points[b] - spec.points[0])
                                                 .dot(spec.points[c] - spec.points[0])));
        }
      }
    }
    if (!(volume > 1e-9 * std::pow(extent.maxCoeff(), 3)))
      s.fail("points", "the points are flat (coplanar): a convex hull needs volume");
    spec.margin = s.number("margin", spec.margin);
    if (!(spec.margin >= 0)) s.fail("margin", "must be >= 0 m");
    if (spec.margin > kMaxRigidLength)
      s.fail("margin", "must be at most 1e6 m (Bullet's inertias must stay finite)");
  } else if (kind == "plane") {
    spec.shape = RigidBodySpec::Shape::kPlane;
    const Eigen::Vector3d n = s.vector3("normal");
    if (n.norm() < 1e-12) s.fail("normal", "must not be zero");
    spec.plane_normal = n.normalized();
    spec.plane_offset = s.number("offset", 0.0);
  } else {
    spec.shape = RigidBodySpec::Shape::kTriangleMesh;
    spec.points = s.vector3List("vertices");
    checkPoints(s, "vertices", spec.points);
    spec.triangles = s.integerTriples("triangles");
    if (spec.triangles.empty()) s.fail("triangles", "a triangle mesh needs triangles");
    for (size_t t = 0; t < spec.triangles.size(); ++t) {
      for (int i : spec.triangles[t]) {
        if (i >= static_cast<int>(spec.points.size())) {
          s.fail("triangles", "element " + std::to_string(t) + ": vertex " + std::to_string(i) +
                                  " does not exist (" + std::to_string(spec.points.size()) +
                                  " vertices)");
        }
      }
    }
  }
  s.finish();
  shape.finish();
}

double readCoefficient(const JsonObject& r, const std::string& key, double fallback) {
  const double value = r.number(key, fallback);
  if (!(value >= 0)) r.fail(key, "must be >= 0");
  return value;
}

// rigid_bodies[].grasper: {"opening", "closing_speed", "grip_force", "button", "jaw":
// {"half_extents", "mass", "friction"}}.
GrasperSpec readGrasper(const JsonObject& g) {
  GrasperSpec spec;
  haptics::GrasperSettings& s = spec.settings;
  s.opening = g.number("opening", s.opening);
  if (!(s.opening > 0)) g.fail("opening", "must be > 0 m (the gap between the open jaws)");
  s.closing_speed = g.number("closing_speed", s.closing_speed);
  if (!(s.closing_speed > 0)) g.fail("closing_speed", "must be > 0 m/s");
  s.grip_force = g.number("grip_force", s.grip_force);
  if (!(s.grip_force > 0)) g.fail("grip_force", "must be > 0 N");
  s.button = g.integer("button", s.button);
  if (s.button < 1 || s.button > 32) g.fail("button", "must be in [1, 32]");
  if (g.has("jaw")) {
    const JsonObject j = g.object("jaw");
    spec.jaw_half_extents = j.vector3("half_extents", spec.jaw_half_extents);
    if (!(spec.jaw_half_extents.minCoeff() > 0)) j.fail("half_extents", "must be > 0");
    if (!(spec.jaw_half_extents.maxCoeff() <= 1e6)) j.fail("half_extents", "must be at most 1e6 m");
    spec.jaw_mass = j.number("mass", spec.jaw_mass);
    if (!(spec.jaw_mass >= kMinRigidMass && spec.jaw_mass <= kMaxRigidMass)) {
      j.fail("mass", formatNumber(spec.jaw_mass) + " kg is outside [" +
                         formatNumber(kMinRigidMass) + ", " + formatNumber(kMaxRigidMass) + "] kg");
    }
    spec.jaw_friction = readCoefficient(j, "friction", spec.jaw_friction);
    j.finish();
  }
  g.finish();
  return spec;
}

}  // namespace

RigidBodySpec readRigidBody(const JsonObject& r, const std::vector<RigidBodySpec>& earlier,
                            const std::string& base_directory) {
  RigidBodySpec spec;
  spec.name = r.name("name");
  for (const RigidBodySpec& other : earlier) {
    if (other.name == spec.name) r.fail("name", "duplicate rigid body name '" + spec.name + "'");
  }
  readShape(r.object("shape"), spec);
  const bool always_static = spec.shape == RigidBodySpec::Shape::kPlane ||
                             spec.shape == RigidBodySpec::Shape::kTriangleMesh;
  if (r.has("kinematic")) {
    for (const JsonObject& m : r.objects("kinematic"))
      spec.kinematic.push_back(parseMotion(m));
    if (spec.kinematic.empty())
      r.fail("kinematic", "needs at least one motion (an empty list: leave the key out)");
    if (always_static) r.fail("kinematic", "planes and triangle meshes are static only");
  }
  spec.mass = r.number("mass", always_static || spec.isKinematic() ? 0.0 : 1.0);
  if (!(spec.mass >= 0)) r.fail("mass", "must be >= 0 kg (0: static)");
  if (always_static && spec.mass != 0)
    r.fail("mass", "planes and triangle meshes are static (mass 0)");
  if (spec.isKinematic() && spec.mass != 0)
    r.fail("mass", "a kinematic body has no mass (leave it out or give 0)");
  if (spec.mass != 0 && (spec.mass < kMinRigidMass || spec.mass > kMaxRigidMass)) {
    r.fail("mass", formatNumber(spec.mass) + " kg is outside [" + formatNumber(kMinRigidMass) +
                       ", " + formatNumber(kMaxRigidMass) +
                       "] kg (Bullet's contact impulses would overflow)");
  }
  spec.pose = parsePose(r, "pose");
  spec.linear_velocity = r.vector3("linear_velocity", Eigen::Vector3d::Zero());
  spec.angular_velocity = r.vector3("angular_velocity", Eigen::Vector3d::Zero());
  if (spec.mass == 0 && (spec.linear_velocity.norm() > 0 || spec.angular_velocity.norm() > 0)) {
    r.fail(r.has("linear_velocity") ? "linear_velocity" : "angular_velocity",
           "only a dynamic body (mass > 0) starts with a velocity; a kinematic one moves by "
           "its 'kinematic' motions");
  }
  spec.friction = readCoefficient(r, "friction", spec.friction);
  spec.restitution = readCoefficient(r, "restitution", spec.restitution);
  if (spec.restitution > 1) r.fail("restitution", "must be <= 1");
  if (r.has("device")) {
    if (spec.mass == 0) {
      r.fail("device",
             "a tool must be a dynamic body (mass > 0): the device pulls it through a spring, "
             "and what it touches stops it");
    }
    spec.device = readToolDevice(r, base_directory);  // device_parser.cpp
  }
  if (r.has("grasper")) {
    if (!spec.device) r.fail("grasper", "a grasper is held by a device: give the body a 'device'");
    if (spec.shape != RigidBodySpec::Shape::kBox)
      r.fail("grasper", "a grasper's palm is a box (its jaws hang below its bottom face)");
    spec.grasper = readGrasper(r.object("grasper"));
  }
  r.finish();
  return spec;
}

RigidBodySpec readGround(const JsonObject& g) {
  RigidBodySpec spec;
  spec.name = "ground";
  spec.shape = RigidBodySpec::Shape::kPlane;
  spec.mass = 0;
  spec.plane_offset = g.number("height", 0.0);
  if (std::abs(spec.plane_offset) > kMaxPlacement) {
    g.fail("height", formatNumber(spec.plane_offset) + " m is beyond the bound " +
                         formatNumber(kMaxPlacement) + " m from the origin");
  }
  spec.friction = readCoefficient(g, "friction", spec.friction);
  spec.restitution = readCoefficient(g, "restitution", spec.restitution);
  if (spec.restitution > 1) g.fail("restitution", "must be <= 1");
  g.finish();
  return spec;
}

Frame RigidBodySpec::poseAt(double t) const {
  // Motions compose in order: F = M_n(t) o ... o M_1(t), each acting on world points.
  Frame moved = pose;
  for (const MotionSpec& m : kinematic) {
    const Frame f = m.frameAt(t);
    moved.origin = f.toWorld(moved.origin);
    moved.rotation = (f.rotation * moved.rotation).normalized();
  }
  return moved;
}

}  // namespace torsion::scene
