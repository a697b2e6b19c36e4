#pragma once
// A scene as parsed from its JSON file (docs/scene-format.md): plain data, validated, with every
// path already resolved relative to the scene file. Building a world from it is scene_builder's
// job.

#include <Eigen/Core>
#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "camera_spec.h"
#include "device_spec.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/bullet/hand.h"
#include "torsion/constraints/frame.h"
#include "torsion/contact/body_pair_contact.h"
#include "torsion/contact/rigid_contact.h"
#include "torsion/contact/self_contact.h"
#include "torsion/fem/element_kind.h"
#include "torsion/fem/material.h"

namespace torsion::scene {

struct BodySpec {
  std::string name;
  std::string mesh_path;  ///< resolved
  Material material;
  Frame pose;
  /// m/s, the centre of mass's velocity at the start ("linear_velocity"); rad/s, a spin about the
  /// centre of mass ("angular_velocity", axis times rate): every node starts at
  /// linear + angular x (x_i - c) (FemBody::setRigidVelocity).
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();
  ElementKind element = ElementKind::kTet4;  ///< "element": "tet4" | "tet10"
  /// "node_order": "cache_friendly" (renumbered inside when that pays; outputs in the file's
  /// numbering) | "file" (the file's numbering inside too).
  NodeNumbering numbering = NodeNumbering::kCacheFriendly;
  /// "self_contact": {"friction", "gap_tolerance", "thickness_factor"}: on when present
  /// (docs/contact.md).
  std::optional<SelfContactSettings> self_contact;
};

/// Which nodes of a body a set takes (rest positions, after the body's pose).
struct NodeSelection {
  enum class Kind { kPlane, kBox, kSphere } kind = Kind::kPlane;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();    ///< plane point / sphere centre
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< plane normal (unit)
  double tolerance = 1e-6;                            ///< plane half-thickness, m
  Eigen::Vector3d min = Eigen::Vector3d::Zero(), max = Eigen::Vector3d::Zero();  ///< box
  double radius = 0;                                                             ///< sphere
};

/// Constant rigid motion of a node set: rotation at angular_velocity about pivot plus translation
/// at linear_velocity, active for t in [start, start + duration], held before and after.
struct MotionSpec {
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  ///< rad/s (axis * rate)
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero();   ///< m/s
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();             ///< m
  double start = 0;                                            ///< s
  double duration = std::numeric_limits<double>::infinity();   ///< s

  /// The frame at time t: identity at and before `start` (the set's capture time is 0).
  Frame frameAt(double t) const;
};

struct NodeSetSpec {
  std::string name;
  std::string body;
  NodeSelection selection;
  bool fixed = true;  ///< true: held in place; false: follows `motion`
  MotionSpec motion;
  Eigen::Vector3d wrench_about = Eigen::Vector3d::Zero();  ///< point for the reported torque
};

/// A hand-plane on one body (docs/design.md section 3): it grabs at `grab_at` the surface patch its
/// plane cuts where the ray from O along i hits, carries it along its trajectory and lets go at
/// `release_at`. The trajectory is either `initial` moved by `motion`, or keyframes (origin
/// interpolated linearly, rotation by slerp, held before the first and after the last).
struct HandSpec {
  std::string name;
  std::string body;
  Frame initial;
  MotionSpec motion;
  std::vector<std::pair<double, Frame>> keyframes;  ///< (time, frame), times strictly increasing
  double grab_at = 0;
  double release_at = std::numeric_limits<double>::infinity();
  HandSettings settings;  ///< speed limit of the grabbed patch (max_drag_strain)
  /// A device moves the hand instead of the script; `initial` is its anchor (device_spec.h).
  std::optional<DeviceSpec> device;

  /// The hand's frame at time t.
  Frame frameAt(double t) const;
};

/// A tool's two jaws (docs/scene-format.md, rigid_bodies[].grasper): boxes hanging below a box
/// palm on prismatic joints along the palm's local x, closed while the device's button is held
/// (torsion/haptics/grasper_coupling.h).
struct GrasperSpec {
  haptics::GrasperSettings settings;
  Eigen::Vector3d jaw_half_extents = Eigen::Vector3d(0.01, 0.03, 0.03);  ///< m
  double jaw_mass = 0.05;                                                ///< kg, each
  double jaw_friction = 0.8;
};

/// A Bullet rigid body (docs/scene-format.md, rigid_bodies[]). Dynamic when mass > 0, static when
/// mass is 0, kinematic when `kinematic` holds a motion: its pose is then scripted (the motions
/// composed in order, applied to `pose`) and it pushes FEM and rigid bodies without being pushed.
struct RigidBodySpec {
  std::string name;
  enum class Shape { kBox, kSphere, kCapsule, kConvexHull, kPlane, kTriangleMesh };
  Shape shape = Shape::kBox;
  Eigen::Vector3d half_extents = Eigen::Vector3d::Constant(0.5);  ///< box
  double radius = 0.5;                                            ///< sphere, capsule
  double half_height = 0.5;             ///< capsule: half the distance between its cap centres
  int axis = 2;                         ///< capsule: 0, 1, 2 = local x, y, z
  std::vector<Eigen::Vector3d> points;  ///< convex hull points / mesh vertices, local
  std::vector<std::array<int, 3>> triangles;  ///< triangle mesh
  double margin = 1e-3;  ///< m, convex hull collision margin (Bullet's default is 0.04)
  Eigen::Vector3d plane_normal = Eigen::Vector3d::UnitZ();  ///< static plane
  double plane_offset = 0;                                  ///< n . x = offset
  double mass = 1;                                          ///< kg; 0 = static
  Frame pose;
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero();   ///< m/s, initial (dynamic)
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  ///< rad/s, initial (dynamic)
  double friction = 0.5;              ///< Bullet's default; a pair's coefficient is the product
  double restitution = 0;             ///< rigid-rigid only (FEM-rigid contact is inelastic)
  std::vector<MotionSpec> kinematic;  ///< non-empty: kinematic, motions composed in order
  /// A device holds the body: it is a tool, pulled toward the device's pose by a virtual
  /// coupling; the device's zero pose sits at `pose` (device_spec.h). Dynamic bodies only.
  std::optional<DeviceSpec> device;
  /// With a device on a box: the tool is a grasper, with two jaws below the box.
  std::optional<GrasperSpec> grasper;

  bool isKinematic() const { return !kinematic.empty(); }
  bool isTool() const { return device.has_value(); }
  /// The scripted pose at time t (kinematic), else `pose`.
  Frame poseAt(double t) const;
};

struct SceneSpec {
  std::string file;  ///< the scene file, for messages
  std::string name;
  WorldSettings world;
  int steps = 100;
  int vtk_every = 0;  ///< steps between the files of the ParaView series (0: none; run_command)
  std::vector<BodySpec> bodies;
  std::vector<NodeSetSpec> node_sets;
  std::vector<HandSpec> hands;
  /// rigid_bodies[], then the .bullet file's bodies (bullet_file_import.h), in file order.
  std::vector<RigidBodySpec> rigid_bodies;
  std::optional<RigidBodySpec> ground;  ///< a static plane, from the top-level "ground"
  /// The .bullet file whose rigid bodies follow rigid_bodies[] in `rigid_bodies`, resolved
  /// against the scene file's directory; empty: none.
  std::string bullet_file;
  CameraSpec camera;  ///< how pictures look at the scene (camera_spec.h)
  /// "fem_contact": contact between FEM bodies (docs/contact.md): {"enabled" (default true),
  /// "friction", "gap_tolerance"}; nullopt: off.
  std::optional<BodyContactSettings> fem_contact = BodyContactSettings{};
  HapticsMode haptics_mode = HapticsMode::kAuto;  ///< not in the file: the CLI's --haptics
  /// Not in the file: the CLI's --sim-priority, the SCHED_FIFO priority of the stepping thread
  /// while threaded haptic loops run (HapticRuntime::setSimulationPriority); 0: unchanged.
  int simulation_priority = 0;
};

}  // namespace torsion::scene
