#include "py_world.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "arithmetic_bounds.h"
#include "json_reader.h"
#include "scene_haptics.h"
#include "scene_parser.h"
#include "torsion/bt_conversions.h"
#include "torsion/bullet/checkpoint_io.h"
#include "torsion/bullet/rigid_health.h"
#include "torsion/format_number.h"

namespace torsion::python {

namespace {

// The scene file's rule for names, and no second part of the kind with the same name.
Status checkName(const std::string& kind, const std::string& name, bool taken) {
  std::string shown;
  for (const char c : name) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte < 0x7f) {
      shown += c;
    } else {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\x%02X", static_cast<unsigned>(byte));
      shown += escaped;
    }
  }
  if (const std::string fault = scene::nameFault(name); !fault.empty())
    return Error{kind + " name '" + shown + "': " + fault};
  if (taken) return Error{kind + " name '" + shown + "': a " + kind + " of that name exists"};
  return Ok{};
}

// A rigid length as the scene parser takes it: finite, > 0, at most kMaxRigidLength.
Status checkLength(const std::string& body, const char* argument, double value) {
  if (value > 0 && value <= scene::kMaxRigidLength) return Ok{};
  return Error{"add_rigid_body '" + body + "': " + argument + " " + formatNumber(value) +
               " m: must be > 0 and at most " + formatNumber(scene::kMaxRigidLength) + " m"};
}

// add_rigid_body's and add_ground's values, checked as readRigidBody / readGround check a scene's.
Status checkRigidSpec(const scene::RigidBodySpec& spec, bool ground) {
  using Shape = scene::RigidBodySpec::Shape;
  const std::string who = ground ? std::string("add_ground") : "add_rigid_body '" + spec.name + "'";
  if (!(spec.friction >= 0 && std::isfinite(spec.friction))) {
    return Error{who + ": friction " + formatNumber(spec.friction) + ": must be finite and >= 0"};
  }
  if (ground) {
    if (!(std::abs(spec.plane_offset) <= scene::kMaxPlacement)) {
      return Error{who + ": height " + formatNumber(spec.plane_offset) +
                   " m: must be finite and within " + formatNumber(scene::kMaxPlacement) +
                   " m of the origin"};
    }
    return Ok{};
  }
  if (spec.shape == Shape::kBox) {
    for (int i = 0; i < 3; ++i) {
      if (Status s = checkLength(spec.name, "half_extents", spec.half_extents[i]); !s) {
        return Error{who + ": half_extents (" + formatNumber(spec.half_extents.x()) + ", " +
                     formatNumber(spec.half_extents.y()) + ", " +
                     formatNumber(spec.half_extents.z()) + ") m: each must be > 0 and at most " +
                     formatNumber(scene::kMaxRigidLength) + " m"};
      }
    }
  }
  if (spec.shape == Shape::kSphere || spec.shape == Shape::kCapsule) {
    if (Status s = checkLength(spec.name, "radius", spec.radius); !s) return s;
  }
  if (spec.shape == Shape::kCapsule) {
    if (Status s = checkLength(spec.name, "half_height", spec.half_height); !s) return s;
  }
  if (!(spec.mass == 0 ||
        (spec.mass >= scene::kMinRigidMass && spec.mass <= scene::kMaxRigidMass))) {
    return Error{who + ": mass " + formatNumber(spec.mass) + " kg: must be 0 (static) or within [" +
                 formatNumber(scene::kMinRigidMass) + ", " + formatNumber(scene::kMaxRigidMass) +
                 "] kg (Bullet divides by it; contact impulses would overflow)"};
  }
  if (!(spec.pose.origin.cwiseAbs().maxCoeff() <= scene::kMaxPlacement)) {
    return Error{who + ": frame position: a coordinate is beyond " +
                 formatNumber(scene::kMaxPlacement) + " m of the origin"};
  }
  if (spec.mass == 0 && spec.linear_velocity.norm() > 0) {
    return Error{who + ": linear_velocity: only a dynamic body (mass > 0) starts with a velocity"};
  }
  return Ok{};
}

}  // namespace

Result<std::unique_ptr<PyWorld>> PyWorld::fromScene(const std::string& name_or_path, int threads,
                                                    const scene::DeviceOverrides& devices,
                                                    FailureKind* kind) {
  *kind = FailureKind::kScene;
  Result<scene::SceneSpec> spec = scene::loadScene(name_or_path);
  if (!spec) return spec.error();
  if (Status applied = scene::applyDeviceOverrides(spec.value(), devices); !applied) {
    *kind = FailureKind::kValue;
    return applied.error();
  }
  std::vector<std::string> mesh_paths;
  for (const scene::BodySpec& body : spec.value().bodies)
    mesh_paths.push_back(body.mesh_path);
  Result<std::unique_ptr<scene::BuiltScene>> built =
      scene::buildScene(std::move(spec).value(), scene::BuildOptions{threads});
  if (!built) {
    // A fault inside a body's mesh file names that file and line after the scene entry.
    for (const std::string& path : mesh_paths) {
      if (built.error().message.find(": " + path + ":") != std::string::npos)
        *kind = FailureKind::kMesh;
    }
    return built.error();
  }
  std::unique_ptr<PyWorld> world(new PyWorld());
  world->scene_ = std::move(built).value();
  world->scene_source_ = name_or_path;
  world->scene_threads_ = threads;
  world->devices_overridden_ = !devices.devices.empty() || !devices.haptics.empty();
  world->recordBuiltMaterials();
  for (const scene::SceneRigidBody& r : world->scene_->rigid_bodies)
    world->registerRigid(r.body);
  return world;
}

namespace {

std::uint64_t nextWorldId() {
  static std::atomic<std::uint64_t> next{1};
  return next++;
}

}  // namespace

PyWorld::PyWorld() : id_(nextWorldId()) {}

PyWorld::PyWorld(const WorldSettings& settings)
    : scene_(std::make_unique<scene::BuiltScene>()), id_(nextWorldId()) {
  scene_->spec.file = "<python>";
  scene_->spec.name = "python";
  scene_->spec.world = settings;
  scene_->world = std::make_unique<FemWorld>(settings);
}

void PyWorld::recordBuiltMaterials() {
  for (const auto& body : world().bodies())
    built_materials_.try_emplace(body->name(), body->model().material());
}

Result<Ok> PyWorld::step(int n, FailureKind* kind, const std::function<bool()>& interrupted) {
  *kind = FailureKind::kUnstable;
  if (!failure_.empty()) return Error{failure_};
  std::vector<NamedRigidBody> rigid;
  for (const scene::SceneRigidBody& r : scene_->rigid_bodies)
    rigid.push_back({r.name, r.body});
  // A failed step has already moved the bodies it reached (and the clock). To leave the last good
  // state instead, the world goes back to an anchor checkpoint and replays the good steps since,
  // which repeat bit for bit. Anchors are taken every kAnchorEvery steps and whenever Python
  // changed the world since (touched()); a checkpoint per step would cost several per cent.
  // Device hands cannot be wound back: no anchors with them.
  const bool can_rewind = !scene_->haptics;
  auto failWith = [&](std::string message) -> Error {
    if (can_rewind && anchor_) {
      const int good_steps = world().stepCount() - 1 - anchor_step_;
      const PyWorldState anchor = std::move(*anchor_);
      (void)restoreState(anchor);
      for (int k = 0; k < good_steps; ++k) {
        applyRigidInputs(k == 0 ? anchor_loads_ : std::vector<RigidLoad>{});
        (void)scene::stepScene(*scene_);
        stepped_ = true;
      }
    }
    failure_ = std::move(message);
    anchor_.reset();
    return Error{failure_};
  };
  for (int k = 0; k < n; ++k) {
    if (can_rewind && (!anchor_ || world().stepCount() - anchor_step_ >= kAnchorEvery)) {
      Result<PyWorldState> state = saveState();
      if (state) {
        anchor_ = std::move(state).value();
        anchor_step_ = world().stepCount();
        anchor_loads_ = loads_;
      }
    }
    applyRigidInputs(loads_);
    loads_.clear();
    Result<WorldStepReport> stepped = scene::stepScene(*scene_);
    if (stepped) stepped_ = true;
    if (!stepped) {
      *kind = FailureKind::kScene;  // a scripted grab that missed: the scene's fault, not fatal
      anchor_.reset();
      return Error{scene_->spec.file + ": " + stepped.error().message};
    }
    const WorldStepReport& report = stepped.value();
    // As the scene runner: a rigid body gone NaN fails the report too, but only the names here
    // say which body it was.
    if (auto fault = findUnhealthyRigidBody(rigid))
      return failWith("step " + std::to_string(report.step) + ": " + fault->message);
    if (!report.ok) return failWith(report.message);
    if (series_) {
      if (Status written = series_->onStep(*scene_, world().stepCount(), -1); !written) {
        *kind = FailureKind::kOutput;
        return endSeriesWith(written.error().message);
      }
    }
    if (interrupted && interrupted()) break;
  }
  return Ok{};
}

Status PyWorld::recordSeries(const std::string& directory, int every, FailureKind* kind) {
  *kind = FailureKind::kValue;
  if (every < 1) return Error{"record_series: every must be >= 1, not " + std::to_string(every)};
  if (directory.empty()) return Error{"record_series: directory is empty"};
  if (series_)
    return Error{"record_series: a series is being recorded (stop_series() ends it first)"};
  // Created here, so a directory that cannot be is a bad argument and nothing was changed.
  const std::filesystem::path dir = std::filesystem::path(directory) / "series";
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return Error{"record_series: " + dir.string() + ": cannot create: " + ec.message()};
  *kind = FailureKind::kOutput;
  Result<std::unique_ptr<series::VtkSeries>> started =
      series::VtkSeries::start(directory, every, *scene_, world().stepCount());
  if (!started) return Error{"record_series: " + started.error().message};
  if (Status listed = started.value()->writeIndex(); !listed)
    return Error{"record_series: " + listed.error().message};
  series_ = std::move(started).value();
  return Ok{};
}

Status PyWorld::stopSeries() {
  if (!series_) return Ok{};
  if (Status written = series_->finish(*scene_, world().stepCount()); !written)
    return endSeriesWith(written.error().message);
  series_steps_written_ = series_->stepsWritten();
  series_.reset();
  return Ok{};
}

Error PyWorld::endSeriesWith(const std::string& message) {
  series_steps_written_ = series_->stepsWritten();
  series_.reset();
  return Error{"record_series: " + message};
}

void PyWorld::applyRigidInputs(const std::vector<RigidLoad>& loads) {
  for (const KinematicTarget& t : targets_) {
    if (btMotionState* motion = t.body->getMotionState()) {
      motion->setWorldTransform(t.target);
    } else {
      t.body->setWorldTransform(t.target);  // without a motion state Bullet reads this one
    }
  }
  for (const RigidLoad& l : loads) {
    l.body->applyCentralForce(toBt(l.load.force));
    l.body->applyTorque(toBt(l.load.torque));
    l.body->activate(true);
  }
}

const scene::SceneRigidBody* PyWorld::sceneRigidBody(const btRigidBody& body) const {
  for (const scene::SceneRigidBody& r : scene_->rigid_bodies) {
    if (r.body == &body) return &r;
  }
  return nullptr;
}

void PyWorld::queueLoad(btRigidBody& body, const Wrench& load) {
  for (RigidLoad& queued : loads_) {
    if (queued.body == &body) {
      queued.load.force += load.force;
      queued.load.torque += load.torque;
      return;
    }
  }
  loads_.push_back({&body, load});
}

Wrench PyWorld::queuedLoad(const btRigidBody& body) const {
  for (const RigidLoad& queued : loads_) {
    if (queued.body == &body) return queued.load;
  }
  return {};
}

void PyWorld::setKinematicTarget(btRigidBody& body, const btTransform& target) {
  for (KinematicTarget& t : targets_) {
    if (t.body == &body) {
      t.target = target;
      return;
    }
  }
  targets_.push_back({&body, target});
}

const btTransform* PyWorld::kinematicTarget(const btRigidBody& body) const {
  for (const KinematicTarget& t : targets_) {
    if (t.body == &body) return &t.target;
  }
  return nullptr;
}

Result<FemBody*> PyWorld::addBody(const std::string& name, const TetMesh& mesh,
                                  const Material& material, const Frame& pose, ElementKind element,
                                  NodeNumbering numbering) {
  if (Status s = checkName("body", name, false); !s) return s.error();
  Result<FemBody*> body = world().addBody(name, mesh, material, pose, element, numbering);
  if (body) {
    parts_added_ = true;
    recordBuiltMaterials();
  }
  return body;
}

Result<int> PyWorld::addNodeSet(const std::string& name, FemBody& body, std::vector<int> nodes,
                                const Eigen::Vector3d& wrench_about) {
  bool taken = false;
  for (const scene::NodeSetHandle& set : scene_->node_sets)
    taken = taken || set.name == name;
  if (Status s = checkName("node set", name, taken); !s) return s.error();
  if (nodes.empty()) return Error{"node set '" + name + "': it holds no node"};
  for (int node : nodes) {
    if (node < 0 || node >= body.model().nodeCount()) {
      return Error{"node set '" + name + "': node " + std::to_string(node) +
                   " is out of range [0, " + std::to_string(body.model().nodeCount()) + ")"};
    }
  }
  scene::NodeSetHandle handle;
  handle.name = name;
  handle.body = &body;
  handle.wrench_about = wrench_about;
  handle.node_count = static_cast<int>(nodes.size());
  handle.group = body.carryNodes(name, std::move(nodes),
                                 FrameMotion([](double) { return Frame{}; }), world().time());
  scene_->node_sets.push_back(handle);
  parts_added_ = true;
  return static_cast<int>(scene_->node_sets.size()) - 1;
}

Result<Hand*> PyWorld::addHand(FemBody& body, const std::string& name,
                               const HandSettings& settings) {
  bool taken = false;
  for (Hand* hand : hands())
    taken = taken || hand->name() == name;
  if (Status s = checkName("hand", name, taken); !s) return s.error();
  own_hands_.push_back(std::make_unique<Hand>(body, name, settings));
  parts_added_ = true;
  return own_hands_.back().get();
}

std::vector<Hand*> PyWorld::hands() {
  std::vector<Hand*> all;
  for (scene::SceneHand& h : scene_->hands)
    all.push_back(h.hand.get());
  for (auto& h : own_hands_)
    all.push_back(h.get());
  return all;
}

const scene::HandSpec* PyWorld::handSpec(const Hand& hand) const {
  for (const scene::SceneHand& h : scene_->hands) {
    if (h.hand.get() == &hand) return &h.spec;
  }
  return nullptr;
}

Result<btRigidBody*> PyWorld::addRigidBody(const scene::RigidBodySpec& spec, bool ground) {
  if (!ground) {
    bool taken = false;
    for (const scene::SceneRigidBody& r : scene_->rigid_bodies)
      taken = taken || r.name == spec.name;
    if (Status s = checkName("rigid body", spec.name, taken); !s) return s.error();
  }
  if (Status s = checkRigidSpec(spec, ground); !s) return s.error();
  scene::SceneRigidBody added = scene::addSceneRigidBody(world(), spec);
  btRigidBody* body = added.body;
  if (!ground) {
    scene_->rigid_bodies.push_back(std::move(added));
    registerRigid(body);
  }
  parts_added_ = true;
  return body;
}

Status PyWorld::removeRigidBody(btRigidBody& body) {
  const auto entry =
      std::find_if(scene_->rigid_bodies.begin(), scene_->rigid_bodies.end(),
                   [&body](const scene::SceneRigidBody& r) { return r.body == &body; });
  if (entry == scene_->rigid_bodies.end())
    return Error{"remove_rigid_body: not a rigid body of this world"};
  const std::string who = "remove_rigid_body '" + entry->name + "': ";
  if (Status removed = world().removeRigidBody(&body); !removed) {
    const std::string prefix = "remove rigid body: ";
    std::string why = removed.error().message;
    if (why.rfind(prefix, 0) == 0) why.erase(0, prefix.size());
    return Error{who + why};
  }
  // The body is gone (a scripted one's motion state may go now); nothing of Python's may point
  // to it any more.
  scene_->rigid_bodies.erase(entry);
  const auto on_body = [&body](const auto& input) { return input.body == &body; };
  loads_.erase(std::remove_if(loads_.begin(), loads_.end(), on_body), loads_.end());
  anchor_loads_.erase(std::remove_if(anchor_loads_.begin(), anchor_loads_.end(), on_body),
                      anchor_loads_.end());
  targets_.erase(std::remove_if(targets_.begin(), targets_.end(), on_body), targets_.end());
  rigid_serials_.erase(&body);
  ++rigid_removals_;
  anchor_.reset();
  stepped_ = false;
  return Ok{};
}

std::uint64_t PyWorld::rigidSerial(const btRigidBody* body) const {
  const auto found = rigid_serials_.find(body);
  return found == rigid_serials_.end() ? 0 : found->second;
}

bool PyWorld::nodeSetScripted(size_t index) const {
  const std::string& name = scene_->node_sets[index].name;
  for (const scene::NodeSetSpec& set : scene_->spec.node_sets) {
    if (set.name == name) return !set.fixed;
  }
  return false;
}

Status PyWorld::moveNodeSet(size_t index, const Frame& pose) {
  const scene::NodeSetHandle& set = scene_->node_sets[index];
  const std::string who = "move_to: node set '" + set.name + "': ";
  if (nodeSetScripted(index))
    return Error{who + "it follows its scene file's motion, which sets it at every step"};
  if (set.body->groups()[static_cast<size_t>(set.group)]->nodes().empty())
    return Error{who + "it was released and holds no node any more"};
  if (!(pose.origin.cwiseAbs().maxCoeff() <= scene::kMaxPlacement)) {
    return Error{who + "position (" + formatNumber(pose.origin.x()) + ", " +
                 formatNumber(pose.origin.y()) + ", " + formatNumber(pose.origin.z()) +
                 ") m: each coordinate must be finite and within " +
                 formatNumber(scene::kMaxPlacement) + " m of the origin"};
  }
  if (!(std::abs(pose.rotation.norm() - 1) <= 1e-6))
    return Error{who + "the quaternion is not a unit quaternion"};
  // The set's frame started at wrench_about with the world's axes: the displacement that puts it
  // at `pose` is x -> R (x - a) + O.
  std::shared_ptr<NodeSetDrive>& drive = drives_[index];
  if (!drive) drive = std::make_shared<NodeSetDrive>();
  drive->goal = pose;
  drive->displacement.rotation = pose.rotation.normalized();
  drive->displacement.origin = pose.origin - drive->displacement.rotation * set.wrench_about;
  installDrives();
  return Ok{};
}

void PyWorld::installDrives() {
  for (const auto& [index, drive] : drives_) {
    const scene::NodeSetHandle& set = scene_->node_sets[index];
    set.body->setGroupMotion(set.group, [shared = drive](double) { return shared->displacement; });
  }
}

Frame PyWorld::nodeSetFrame(size_t index) {
  const scene::NodeSetHandle& set = scene_->node_sets[index];
  const CarriedNodes& group = *set.body->groups()[static_cast<size_t>(set.group)];
  if (const auto driven = drives_.find(index); driven != drives_.end() && !group.nodes().empty())
    return driven->second->goal;
  const double end = world().time() + world().settings().solver.time_step;
  const Frame displacement = group.frameAt(end);
  Frame pose;
  pose.rotation = displacement.rotation;
  pose.origin = displacement.toWorld(set.wrench_about);
  return pose;
}

Status PyWorld::setFemContact(const std::optional<BodyContactSettings>& settings,
                              bool refuse_touching) {
  FemSoftBodySolver& solver = world().femSolver();
  if (settings) {
    if (Status valid = settings->validate(); !valid) return valid;
    const FemContactIslands* on = solver.femContact();
    const auto same = [](const BodyContactSettings& a, const BodyContactSettings& b) {
      return a.friction == b.friction && a.gap_tolerance == b.gap_tolerance &&
             a.thickness_factor == b.thickness_factor && a.margin == b.margin &&
             a.max_depth == b.max_depth && a.edge_edge == b.edge_edge;
    };
    // The same settings again keep the pairs and their warm starts.
    if (on == nullptr || !same(on->settings(), *settings)) {
      if (Status set = solver.setFemContact(settings); !set) return set;
    }
    solver.setUnsupportedContact(UnsupportedContact::kError);
  } else {
    (void)solver.setFemContact(std::nullopt);
    solver.setUnsupportedContact(refuse_touching ? UnsupportedContact::kError
                                                 : UnsupportedContact::kWarn);
  }
  fem_contact_changed_ = true;
  return Ok{};
}

Status PyWorld::setGravity(const Eigen::Vector3d& gravity) {
  if (Status bounded = scene::checkGravity(gravity); !bounded)
    return Error{"gravity: " + bounded.error().message};
  if (Status set = world().setGravity(gravity); !set) return set;
  return Ok{};
}

Status PyWorld::setTimeStep(double dt) {
  if (scene_->haptics) {
    return Error{"dt: the scene's device hands run haptic loops at the dt they started with (" +
                 formatNumber(world().settings().solver.time_step) + " s)"};
  }
  SolverSettings solver = world().settings().solver;
  solver.time_step = dt;
  if (Status set = world().setSolverSettings(solver); !set)
    return Error{"dt: " + set.error().message};
  return Ok{};
}

Result<PyWorldState> PyWorld::saveState() {
  if (scene_->haptics) {
    return Error{
        "save_state: the scene's device hands run haptic loops, whose devices cannot be "
        "wound back"};
  }
  PyWorldState state;
  state.world = world().checkpoint();
  for (Hand* hand : hands())
    state.hands.push_back(hand->checkpoint());
  for (const scene::SceneHand& h : scene_->hands)
    state.released.push_back(h.released);
  state.node_set_count = scene_->node_sets.size();
  state.failure = failure_;
  state.time = state.world.fem.time;
  state.source = id_;
  state.rigid_removals = rigid_removals_;
  return state;
}

namespace {

// The material values a body is built with, as a line of the Python fields: "E nu rho
// mass_damping stiffness_damping volumetric_strain barrier_threshold barrier_stiffness", each
// number in hexadecimal floating point (exact).
std::string materialLine(const Material& m) {
  std::string line;
  for (double v :
       {m.youngs_modulus, m.poisson_ratio, m.density, m.mass_damping, m.stiffness_damping}) {
    char text[40];
    std::snprintf(text, sizeof text, "%a ", v);
    line += text;
  }
  line += toString(m.volumetric_strain);
  for (double v : {m.barrier_threshold, m.barrier_stiffness}) {
    char text[40];
    std::snprintf(text, sizeof text, " %a", v);
    line += text;
  }
  return line;
}

// What differs between the materials a body was built with in the saved world (`saved`, a
// materialLine) and here (`here`), e.g. "E 100000 Pa in the checkpoint, 200000 Pa here".
std::string materialDifference(const std::string& saved, const Material& here) {
  std::istringstream in(saved);
  std::string field[8];
  for (std::string& f : field)
    in >> f;
  const char* names[] = {"E", "nu", "rho", "mass_damping", "stiffness_damping"};
  const char* units[] = {" Pa", "", " kg/m^3", " 1/s", " s"};
  const double values[] = {here.youngs_modulus, here.poisson_ratio, here.density, here.mass_damping,
                           here.stiffness_damping};
  std::string out;
  auto add = [&out](const std::string& part) { out += (out.empty() ? "" : ", ") + part; };
  for (int k = 0; k < 5; ++k) {
    const double was = std::strtod(field[k].c_str(), nullptr);
    if (was != values[k]) {
      add(std::string(names[k]) + " " + formatNumber(was) + units[k] + " in the checkpoint, " +
          formatNumber(values[k]) + units[k] + " here");
    }
  }
  if (field[5] != toString(here.volumetric_strain))
    add("volumetric_strain " + field[5] + " in the checkpoint, " +
        toString(here.volumetric_strain) + " here");
  const double barrier[] = {here.barrier_threshold, here.barrier_stiffness};
  const char* barrier_names[] = {"barrier_threshold", "barrier_stiffness"};
  for (int k = 0; k < 2; ++k) {
    const double was = std::strtod(field[6 + k].c_str(), nullptr);
    if (was != barrier[k]) {
      add(std::string(barrier_names[k]) + " " + formatNumber(was) + " in the checkpoint, " +
          formatNumber(barrier[k]) + " here");
    }
  }
  return out.empty() ? "its material differs" : out;
}

}  // namespace

// PyWorldState's own fields travel as the checkpoint's extra bytes: "<node sets>\n<released
// flags as 0 and 1>\n<body count>\n<per body: name\n materialLine\n><failure>".
std::string PyWorld::serialize(const PyWorldState& state) {
  std::string extra = std::to_string(state.node_set_count) + "\n";
  for (bool released : state.released)
    extra += released ? '1' : '0';
  extra += "\n" + std::to_string(built_materials_.size()) + "\n";
  for (const auto& [name, material] : built_materials_)
    extra += name + "\n" + materialLine(material) + "\n";
  extra += state.failure;
  return writeCheckpoint(world(), state.world, hands(), state.hands, extra);
}

namespace {

Result<PyWorldState> deserialize(const std::string& bytes, FemWorld& world,
                                 const std::vector<Hand*>& hands, size_t scene_hands,
                                 const std::map<std::string, Material>& built_materials) {
  Result<StoredCheckpoint> stored = readCheckpoint(bytes, world, hands);
  if (!stored) return Error{"restore_state: " + stored.error().message};
  PyWorldState state;
  state.world = std::move(stored.value().world);
  state.hands = std::move(stored.value().hands);
  state.time = state.world.fem.time;
  const std::string& extra = stored.value().extra;
  const size_t first = extra.find('\n');
  const size_t second = first == std::string::npos ? first : extra.find('\n', first + 1);
  const std::string counted = extra.substr(0, first);
  if (second == std::string::npos || counted.empty() ||
      counted.find_first_not_of("0123456789") != std::string::npos) {
    return Error{"restore_state: the checkpoint is corrupted (its Python fields)"};
  }
  state.node_set_count = std::stoul(counted);
  for (size_t k = first + 1; k < second; ++k)
    state.released.push_back(extra[k] == '1');
  if (state.released.size() != scene_hands) {
    return Error{"restore_state: the checkpoint was saved from another world: it has " +
                 std::to_string(state.released.size()) + " scene hands, this world " +
                 std::to_string(scene_hands)};
  }
  // The bodies' materials as built; readCheckpoint has matched the bodies by name.
  std::istringstream lines(extra.substr(second + 1));
  std::string line;
  size_t bodies = 0;
  if (!std::getline(lines, line) || line.empty() ||
      line.find_first_not_of("0123456789") != std::string::npos) {
    return Error{"restore_state: the checkpoint is corrupted (its Python fields)"};
  }
  bodies = std::stoul(line);
  for (size_t b = 0; b < bodies; ++b) {
    std::string name, material;
    if (!std::getline(lines, name) || !std::getline(lines, material))
      return Error{"restore_state: the checkpoint is corrupted (its Python fields)"};
    const auto here = built_materials.find(name);
    if (here == built_materials.end()) continue;  // readCheckpoint names a missing body
    if (material != materialLine(here->second)) {
      return Error{"restore_state: the checkpoint was saved from another world: body '" + name +
                   "' was built with another material (" +
                   materialDifference(material, here->second) + ")"};
    }
  }
  const std::streamoff read = lines.tellg();
  state.failure = read < 0 ? std::string() : extra.substr(second + 1 + static_cast<size_t>(read));
  return state;
}

}  // namespace

Status PyWorld::restoreState(const PyWorldState& state) {
  // A state of another world (or one unpickled) is read from its bytes for this world: its
  // in-memory part points into the world that saved it, and reading names what differs.
  if (!state.in_memory || state.source != id_) {
    if (state.bytes.empty())
      return Error{"restore_state: the state was saved from another world and holds no bytes"};
    Result<PyWorldState> read =
        deserialize(state.bytes, world(), hands(), scene_->hands.size(), built_materials_);
    if (!read) return read.error();
    read.value().source = id_;
    read.value().rigid_removals = rigid_removals_;  // its bytes were read for the world as it is
    return restoreState(read.value());
  }
  std::vector<Hand*> all = hands();
  if (all.size() != state.hands.size() || state.node_set_count != scene_->node_sets.size()) {
    return Error{"restore_state: hands or node sets were added since the state was saved"};
  }
  if (state.rigid_removals != rigid_removals_)
    return Error{"restore_state: a rigid body was removed since the state was saved"};
  if (Status restored = world().restore(state.world); !restored) return restored;
  for (size_t h = 0; h < all.size(); ++h)
    all[h]->restore(state.hands[h]);
  for (size_t h = 0; h < scene_->hands.size(); ++h)
    scene_->hands[h].released = state.released[h];
  failure_ = state.failure;
  installDrives();
  anchor_.reset();
  stepped_ = false;
  return Ok{};
}

}  // namespace torsion::python
