#include "scene_parser.h"

#include <filesystem>

#include "arithmetic_bounds.h"
#include "bullet_file_import.h"
#include "camera_spec.h"
#include "device_parser.h"
#include "json_reader.h"
#include "rigid_body_parser.h"
#include "scene_catalog.h"
#include "torsion/device/json_check.h"
#include "torsion/format_number.h"
#include "torsion/mesh/mesh_io.h"

namespace torsion::scene {

namespace {

// Material::validate and SolverSettings::validate word a fault "<subject>: <detail>", the subject
// being the object this parser reads there ("material", "solver"). The fault goes to that
// object's key path with the detail; a message not worded so is kept whole.
[[noreturn]] void failValidation(const JsonObject& object, const std::string& subject,
                                 const Error& error) {
  const std::string prefix = subject + ": ";
  const std::string& message = error.message;
  const bool worded = message.compare(0, prefix.size(), prefix) == 0;
  object.fail("", worded ? message.substr(prefix.size()) : message);
}

// {"axis": [3], "angle": rad} -> a rotation; the axis need not be unit, but not zero.
Eigen::Quaterniond readAxisAngle(const JsonObject& aa) {
  const Eigen::Vector3d axis = aa.vector3("axis");
  if (axis.norm() < 1e-12) aa.fail("axis", "must not be zero");
  const Eigen::Quaterniond rotation(Eigen::AngleAxisd(aa.number("angle"), axis.normalized()));
  aa.finish();
  return rotation;
}

Frame readPose(const JsonObject& parent, const std::string& key) {
  Frame pose;
  if (!parent.has(key)) return pose;
  const JsonObject p = parent.object(key);
  pose.origin = p.vector3("position", Eigen::Vector3d::Zero());
  if (pose.origin.cwiseAbs().maxCoeff() > kMaxPlacement) {
    p.fail("position", "a coordinate of " + formatNumber(pose.origin.cwiseAbs().maxCoeff()) +
                           " m is beyond the bound " + formatNumber(kMaxPlacement) +
                           " m (a body's coordinates would lose their digits)");
  }
  if (p.has("axis_angle")) pose.rotation = readAxisAngle(p.object("axis_angle"));
  p.finish();
  return pose;
}

Material readMaterial(const JsonObject& m) {
  Material material;
  material.youngs_modulus = m.number("youngs_modulus");
  material.poisson_ratio = m.number("poisson_ratio");
  material.density = m.number("density");
  material.mass_damping = m.number("mass_damping", material.mass_damping);
  material.stiffness_damping = m.number("stiffness_damping", material.stiffness_damping);
  material.barrier_threshold = m.number("barrier_threshold", material.barrier_threshold);
  material.barrier_stiffness = m.number("barrier_stiffness", material.barrier_stiffness);
  const std::string volumetric =
      m.string("volumetric_strain", toString(material.volumetric_strain));
  if (auto kind = parseVolumetricStrain(volumetric)) {
    material.volumetric_strain = *kind;
  } else {
    m.fail("volumetric_strain",
           "'" + volumetric + "' is not a volumetric strain (element or nodal_average)");
  }
  const std::string law = m.string("law", toString(material.law));
  if (auto kind = parseMaterialLaw(law)) {
    material.law = *kind;
  } else {
    m.fail("law",
           "'" + law + "' is not a material law (corotated, stable_neo_hookean or mooney_rivlin)");
  }
  material.mooney_rivlin_c2_fraction =
      m.number("mooney_rivlin_c2_fraction", material.mooney_rivlin_c2_fraction);
  if (material.hyperelastic() && material.volumetric_strain == VolumetricStrain::kNodalAverage) {
    m.fail("volumetric_strain", std::string("nodal_average is a corotated option (law ") +
                                    toString(material.law) + " takes element)");
  }
  m.finish();
  Status valid = material.validate();
  if (!valid) failValidation(m, "material", valid.error());
  return material;
}

SolverSettings readSolver(const JsonObject& s) {
  SolverSettings settings;
  settings.time_step = s.number("dt", settings.time_step);
  const std::string solver = s.string("linear_solver", "cg");
  if (solver == "cg") {
    settings.linear_solver = LinearSolverKind::kConjugateGradient;
  } else if (solver == "cholmod") {
    settings.linear_solver = LinearSolverKind::kCholmod;
  } else {
    s.fail("linear_solver", "'" + solver + "' is not one of: cg, cholmod");
  }
  const std::string preconditioner = s.string("preconditioner", "block_jacobi");
  if (preconditioner == "jacobi") {
    settings.preconditioner = PreconditionerKind::kJacobi;
  } else if (preconditioner == "block_jacobi") {
    settings.preconditioner = PreconditionerKind::kBlockJacobi;
  } else if (preconditioner == "lagged_cholesky") {
    settings.preconditioner = PreconditionerKind::kLaggedCholesky;
  } else if (preconditioner == "incomplete_cholesky") {
    settings.preconditioner = PreconditionerKind::kIncompleteCholesky;
  } else if (preconditioner == "two_level") {
    settings.preconditioner = PreconditionerKind::kTwoLevel;
  } else {
    s.fail("preconditioner", "'" + preconditioner +
                                 "' is not one of: jacobi, block_jacobi, lagged_cholesky, "
                                 "incomplete_cholesky, two_level");
  }
  settings.refactor_interval = s.integer("refactor_interval", settings.refactor_interval);
  settings.refactor_iterations = s.integer("refactor_iterations", settings.refactor_iterations);
  settings.tolerance = s.number("tolerance", settings.tolerance);
  settings.max_iterations = s.integer("max_iterations", settings.max_iterations);
  settings.newton_tolerance = s.number("newton_tolerance", settings.newton_tolerance);
  settings.newton_max_iterations =
      s.integer("newton_max_iterations", settings.newton_max_iterations);
  settings.threads = s.integer("threads", settings.threads);
  settings.max_speed = s.number("max_speed", settings.max_speed);
  s.finish();
  Status valid = settings.validate();
  if (!valid) failValidation(s, "solver", valid.error());
  return settings;
}

NodeSelection readSelection(const JsonObject& s) {
  NodeSelection sel;
  const std::string kind = s.oneOf({"plane", "box", "sphere"});
  const JsonObject o = s.object(kind);
  if (kind == "plane") {
    sel.kind = NodeSelection::Kind::kPlane;
    sel.point = o.vector3("point");
    const Eigen::Vector3d n = o.vector3("normal");
    if (n.norm() < 1e-12) o.fail("normal", "must not be zero");
    sel.normal = n.normalized();
    sel.tolerance = o.number("tolerance", 1e-6);
    if (!(sel.tolerance >= 0)) o.fail("tolerance", "must be >= 0");
  } else if (kind == "box") {
    sel.kind = NodeSelection::Kind::kBox;
    sel.min = o.vector3("min");
    sel.max = o.vector3("max");
    if (!(sel.max.array() >= sel.min.array()).all()) o.fail("max", "must be >= min on every axis");
  } else {
    sel.kind = NodeSelection::Kind::kSphere;
    sel.point = o.vector3("center");
    sel.radius = o.number("radius");
    if (!(sel.radius > 0)) o.fail("radius", "must be > 0");
  }
  o.finish();
  s.finish();
  return sel;
}

// A hand frame: origin plus either axis_angle or the in-plane axes i and j (k = i x j). i and j
// must be orthonormal: a degenerate rotation is refused rather than silently repaired.
Frame readHandFrame(const JsonObject& f) {
  Frame frame;
  frame.origin = f.vector3("origin");
  const bool has_axes = f.has("i") || f.has("j");
  if (f.has("axis_angle") && has_axes)
    f.fail("axis_angle", "give either axis_angle or i and j, not both");
  if (f.has("axis_angle")) {
    frame.rotation = readAxisAngle(f.object("axis_angle"));
  } else if (has_axes) {
    const Eigen::Vector3d i = f.vector3("i"), j = f.vector3("j");
    if (std::abs(i.norm() - 1) > 1e-6 || std::abs(j.norm() - 1) > 1e-6 ||
        std::abs(i.dot(j)) > 1e-6) {
      f.fail("i", "degenerate rotation: i and j must be orthonormal (|i| = " +
                      std::to_string(i.norm()) + ", |j| = " + std::to_string(j.norm()) +
                      ", i.j = " + std::to_string(i.dot(j)) + ")");
    }
    Eigen::Matrix3d R;
    R << i, j, i.cross(j);
    frame.rotation = Eigen::Quaterniond(R).normalized();
  }
  f.finish();
  return frame;
}

MotionSpec readMotion(const JsonObject& m) {
  MotionSpec motion;
  motion.angular_velocity = m.vector3("angular_velocity", Eigen::Vector3d::Zero());
  motion.linear_velocity = m.vector3("linear_velocity", Eigen::Vector3d::Zero());
  motion.pivot = m.vector3("pivot", Eigen::Vector3d::Zero());
  motion.start = m.number("start", 0.0);
  if (m.has("duration")) {
    motion.duration = m.number("duration");
    if (!(motion.duration >= 0)) m.fail("duration", "must be >= 0 s");
  }
  if (!(motion.start >= 0)) m.fail("start", "must be >= 0 s");
  m.finish();
  return motion;
}

HandSpec readHand(const JsonObject& h, const std::string& base_directory) {
  HandSpec hand;
  hand.name = h.name("name");
  hand.body = h.string("body");
  if (h.has("device")) hand.device = readDevice(h, base_directory);  // device_parser.cpp
  if (h.has("keyframes")) {
    if (h.has("frame") || h.has("motion"))
      h.fail("keyframes", "give either keyframes or frame (+ motion), not both");
    const std::vector<JsonObject> keys = h.objects("keyframes");
    if (keys.empty()) h.fail("keyframes", "needs at least one keyframe");
    for (size_t k = 0; k < keys.size(); ++k) {
      const double time = keys[k].number("time");
      if (k > 0 && !(time > hand.keyframes.back().first)) {
        keys[k].fail("time", formatNumber(time) + " is not after the previous keyframe's " +
                                 formatNumber(hand.keyframes.back().first) +
                                 ": keyframes must be in time order");
      }
      hand.keyframes.emplace_back(time, readHandFrame(keys[k]));
    }
  } else {
    hand.initial = readHandFrame(h.object("frame"));
    if (h.has("motion")) hand.motion = readMotion(h.object("motion"));
  }
  hand.grab_at = h.number("grab_at", 0.0);
  if (!(hand.grab_at >= 0)) h.fail("grab_at", "must be >= 0 s");
  if (h.has("release_at")) {
    hand.release_at = h.number("release_at");
    if (!(hand.release_at > hand.grab_at)) h.fail("release_at", "must be after grab_at");
  }
  hand.settings.max_drag_strain = h.number("max_drag_strain", hand.settings.max_drag_strain);
  if (!hand.settings.validate().ok())
    h.fail("max_drag_strain", "must be >= 0 (0 turns the hand's speed limit off)");
  h.finish();
  return hand;
}

}  // namespace

Frame parsePose(const JsonObject& parent, const std::string& key) {
  return readPose(parent, key);
}

MotionSpec parseMotion(const JsonObject& m) {
  return readMotion(m);
}

Frame MotionSpec::frameAt(double t) const {
  const double tau = std::clamp(t - start, 0.0, duration);
  Frame frame;
  const double angle = angular_velocity.norm() * tau;
  if (angle > 0) frame.rotation = Eigen::AngleAxisd(angle, angular_velocity.normalized());
  // Rotation about the pivot, then translation: p -> R (p - c) + c + v tau.
  frame.origin = pivot - (frame.rotation * pivot) + linear_velocity * tau;
  return frame;
}

Frame HandSpec::frameAt(double t) const {
  if (keyframes.empty()) {
    const Frame m = motion.frameAt(t);
    Frame f;
    f.origin = m.toWorld(initial.origin);
    f.rotation = m.rotation * initial.rotation;
    return f;
  }
  if (t <= keyframes.front().first) return keyframes.front().second;
  if (t >= keyframes.back().first) return keyframes.back().second;
  size_t k = 1;
  while (keyframes[k].first < t)
    ++k;
  const auto& [t0, f0] = keyframes[k - 1];
  const auto& [t1, f1] = keyframes[k];
  const double s = (t - t0) / (t1 - t0);
  Frame f;
  f.origin = (1 - s) * f0.origin + s * f1.origin;
  f.rotation = f0.rotation.slerp(s, f1.rotation);
  return f;
}

namespace {

std::string resolved(const std::string& path, const std::string& base_directory) {
  const std::filesystem::path p(path);
  return p.is_absolute() ? p.string() : (std::filesystem::path(base_directory) / p).string();
}

bool hasBody(const SceneSpec& scene, const std::string& name) {
  bool known = false;
  for (const BodySpec& body : scene.bodies)
    known = known || body.name == name;
  return known;
}

// name, gravity, solver, steps.
// "fem_contact": {"enabled" (default true), "friction", "gap_tolerance"}.
std::optional<BodyContactSettings> readFemContact(const JsonObject& root) {
  const JsonObject c = root.object("fem_contact");
  const bool enabled = c.boolean("enabled", true);
  BodyContactSettings settings;
  settings.friction = c.number("friction", settings.friction);
  settings.gap_tolerance = c.number("gap_tolerance", settings.gap_tolerance);
  c.finish();
  if (!enabled) return std::nullopt;
  if (Status valid = settings.validate(); !valid) root.fail("fem_contact", valid.error().message);
  return settings;
}

void readWorld(const JsonObject& root, const std::string& file_name, SceneSpec& scene) {
  scene.name = root.string("name", std::filesystem::path(file_name).stem().string());
  scene.world.gravity = root.vector3("gravity", Eigen::Vector3d(0, 0, -9.81));
  if (Status carried = checkGravity(scene.world.gravity); !carried)
    root.fail("gravity", carried.error().message);
  if (root.has("solver")) scene.world.solver = readSolver(root.object("solver"));
  scene.steps = root.integer("steps", scene.steps);
  if (scene.steps < 1) root.fail("steps", "must be >= 1");
  scene.vtk_every = root.integer("vtk_every", scene.vtk_every);  // ParaView series, 0: none
  if (scene.vtk_every < 0) root.fail("vtk_every", "must be >= 0 (0: no series)");
  if (root.has("fem_contact")) scene.fem_contact = readFemContact(root);
}

// "linear_velocity" (m/s) and "angular_velocity" (rad/s, about the centre of mass): the body's
// rigid motion at the start, bounded so that the first step's arithmetic keeps its digits.
void readStartingVelocity(const JsonObject& b, BodySpec& body) {
  body.linear_velocity = b.vector3("linear_velocity", Eigen::Vector3d::Zero());
  if (body.linear_velocity.norm() > kMaxInitialSpeed) {
    b.fail("linear_velocity", "speed " + formatNumber(body.linear_velocity.norm()) +
                                  " m/s is above the bound " + formatNumber(kMaxInitialSpeed) +
                                  " m/s");
  }
  body.angular_velocity = b.vector3("angular_velocity", Eigen::Vector3d::Zero());
  if (body.angular_velocity.norm() > kMaxInitialSpin) {
    b.fail("angular_velocity", "spin " + formatNumber(body.angular_velocity.norm()) +
                                   " rad/s is above the bound " + formatNumber(kMaxInitialSpin) +
                                   " rad/s");
  }
}

BodySpec readBody(const JsonObject& b, const SceneSpec& scene, const std::string& base_directory) {
  BodySpec body;
  body.name = b.name("name");
  for (const BodySpec& other : scene.bodies) {
    if (other.name == body.name) b.fail("name", "duplicate body name '" + body.name + "'");
  }
  const std::string mesh = b.string("mesh");
  body.mesh_path = resolved(mesh, base_directory);
  body.material = readMaterial(b.object("material"));
  body.pose = readPose(b, "pose");
  readStartingVelocity(b, body);
  const std::string element = b.string("element", "tet4");
  if (auto kind = parseElementKind(element)) {
    body.element = *kind;
  } else {
    b.fail("element", "'" + element + "' is not an element kind (tet4 or tet10)");
  }
  if (body.element == ElementKind::kTet10 &&
      body.material.volumetric_strain == VolumetricStrain::kNodalAverage) {
    b.fail("material", "volumetric_strain nodal_average is a tet4 option (tet10 does not lock)");
  }
  const std::string order = b.string("node_order", "cache_friendly");
  if (order == "file") {
    body.numbering = NodeNumbering::kAsGiven;
  } else if (order != "cache_friendly") {
    b.fail("node_order", "'" + order + "' is not a node order (cache_friendly or file)");
  }
  if (b.has("self_contact")) {
    const JsonObject c = b.object("self_contact");
    SelfContactSettings self;
    self.friction = c.number("friction", self.friction);
    self.gap_tolerance = c.number("gap_tolerance", self.gap_tolerance);
    self.thickness_factor = c.number("thickness_factor", self.thickness_factor);
    c.finish();
    if (Status valid = self.validate(); !valid) b.fail("self_contact", valid.error().message);
    body.self_contact = self;
  }
  b.finish();
  return body;
}

NodeSetSpec readNodeSet(const JsonObject& s, const SceneSpec& scene) {
  NodeSetSpec set;
  set.name = s.name("name");
  for (const NodeSetSpec& other : scene.node_sets) {
    if (other.name == set.name) s.fail("name", "duplicate node set name '" + set.name + "'");
  }
  set.body = s.string("body");
  if (!hasBody(scene, set.body)) s.fail("body", "no body named '" + set.body + "'");
  set.selection = readSelection(s.object("select"));
  set.fixed = !s.has("motion");
  if (!set.fixed) set.motion = readMotion(s.object("motion"));
  set.wrench_about = s.vector3("wrench_about", set.motion.pivot);
  s.finish();
  return set;
}

// A hand, checked against the bodies, the other hands and the node sets already read.
HandSpec readSceneHand(const JsonObject& h, const SceneSpec& scene,
                       const std::string& base_directory) {
  HandSpec hand = readHand(h, base_directory);
  if (!hasBody(scene, hand.body)) h.fail("body", "no body named '" + hand.body + "'");
  for (const HandSpec& other : scene.hands) {
    if (other.name == hand.name) h.fail("name", "duplicate hand name '" + hand.name + "'");
  }
  // Node sets and hands share wrench.csv's columns ("<name>.fx").
  for (const NodeSetSpec& set : scene.node_sets) {
    if (set.name == hand.name)
      h.fail("name",
             "'" + hand.name + "' is also a node set's name: both would be columns of wrench.csv");
  }
  return hand;
}

// A rigid body of rigid_bodies or of the .bullet file, checked against those read before it.
void readSceneRigidBody(const JsonObject& r, const std::string& base_directory, SceneSpec& scene) {
  scene.rigid_bodies.push_back(readRigidBody(r, scene.rigid_bodies, base_directory));
  // The series names a rigid body's files "rigid_<name>_<step>.vtu", a FEM body's
  // "<name>_<step>.vtu" (docs/outputs.md): FEM body "rigid_X" and rigid body "X" would share
  // them.
  const std::string& name = scene.rigid_bodies.back().name;
  for (const BodySpec& body : scene.bodies) {
    if (body.name == "rigid_" + name)
      r.fail("name", "rigid body '" + name + "' and FEM body '" + body.name +
                         "' would write the same series files (series/rigid_" + name +
                         "_<step>.vtu): rename one");
  }
}

// Rigid bodies, the ground, a .bullet file's rigid bodies and the camera.
void readSurroundings(const JsonObject& root, const std::string& base_directory, SceneSpec& scene) {
  for (const JsonObject& r : root.objects("rigid_bodies"))
    readSceneRigidBody(r, base_directory, scene);
  if (root.has("ground")) scene.ground = readGround(root.object("ground"));
  if (root.has("bullet_file")) {
    scene.bullet_file = resolved(root.string("bullet_file"), base_directory);
    Result<nlohmann::json> imported = importBulletFile(scene.bullet_file);
    if (!imported) root.fail("bullet_file", imported.error().message);
    // Its faults read "<scene>: bullet_file: <file>: rigid_bodies[k].<key>: ...".
    const std::string where = scene.file + ": bullet_file: " + scene.bullet_file;
    const JsonObject file(imported.value(), "", where);
    for (const JsonObject& r : file.objects("rigid_bodies"))
      readSceneRigidBody(r, base_directory, scene);
    file.finish();
  }
  scene.camera = readCameraSpec(root);
}

}  // namespace

// The scene as its stages: strict JSON, the world, the FEM bodies, the node sets, the hands, the
// surroundings, then no unknown key and a valid world. Faults are SceneFaults (json_reader.h).
Result<SceneSpec> parseScene(std::string_view text, const std::string& file_name,
                             const std::string& base_directory) {
  // A strict pass first: duplicate keys, numbers beyond a double and syntax, with a position.
  if (const auto fault = device::findJsonTextFault(text)) {
    const std::string where =
        fault->line > 0 ? ":" + std::to_string(fault->line) + ":" + std::to_string(fault->column)
                        : std::string();
    return Error{file_name + where + ": invalid JSON: " + fault->what};
  }
  const nlohmann::json json = nlohmann::json::parse(text.begin(), text.end());
  try {
    SceneSpec scene;
    scene.file = file_name;
    const JsonObject root(json, "", file_name);
    readWorld(root, file_name, scene);
    for (const JsonObject& b : root.objects("bodies"))
      scene.bodies.push_back(readBody(b, scene, base_directory));
    if (scene.bodies.empty()) root.fail("bodies", "a scene needs at least one FEM body");
    for (const JsonObject& s : root.objects("node_sets"))
      scene.node_sets.push_back(readNodeSet(s, scene));
    for (const JsonObject& h : root.objects("hands"))
      scene.hands.push_back(readSceneHand(h, scene, base_directory));
    readSurroundings(root, base_directory, scene);
    root.finish();
    Status world_ok = scene.world.validate();
    if (!world_ok) return Error{SceneFault{file_name, "", world_ok.error().message}.text()};
    return scene;
  } catch (const JsonFault& fault) {
    return Error{fault.fault.text()};
  }
}

Result<SceneSpec> loadScene(const std::string& path_or_name) {
  Result<std::string> path = resolveScene(path_or_name);
  if (!path) return path.error();
  Result<std::string> text = readTextFile(path.value());
  if (!text) return text.error();
  return parseScene(text.value(), path.value(),
                    std::filesystem::path(path.value()).parent_path().string());
}

}  // namespace torsion::scene
