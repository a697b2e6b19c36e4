#include "scene_builder.h"

#include "arithmetic_bounds.h"
#include "scene_haptics.h"
#include "torsion/format_number.h"
#include "torsion/mesh/mesh_io.h"

namespace torsion::scene {

std::vector<int> selectNodes(const TetMesh& mesh, const NodeSelection& selection) {
  std::vector<int> nodes;
  for (int i = 0; i < mesh.nodeCount(); ++i) {
    const Eigen::Vector3d& p = mesh.restPositions()[static_cast<size_t>(i)];
    bool inside = false;
    switch (selection.kind) {
      case NodeSelection::Kind::kPlane:
        inside = std::abs(selection.normal.dot(p - selection.point)) <= selection.tolerance;
        break;
      case NodeSelection::Kind::kBox:
        inside = (p.array() >= selection.min.array()).all() &&
                 (p.array() <= selection.max.array()).all();
        break;
      case NodeSelection::Kind::kSphere:
        inside = (p - selection.point).norm() <= selection.radius;
        break;
    }
    if (inside) nodes.push_back(i);
  }
  return nodes;
}

Status driveHands(BuiltScene& scene) {
  const double now = scene.world->time();
  const double dt = scene.world->settings().solver.time_step;
  // Half a step of slack so that a time written in the scene is reached despite round-off.
  const double reached = now + 0.5 * dt;
  for (size_t h = 0; h < scene.hands.size(); ++h) {
    SceneHand& s = scene.hands[h];
    if (s.spec.device) continue;  // moved by its device through SceneHaptics
    if (!s.scripted) continue;
    if (s.hand->grabbed() && reached >= s.spec.release_at) {
      s.hand->release();
      s.released = true;
    }
    if (!s.hand->grabbed() && !s.released && reached >= s.spec.grab_at) {
      Result<int> grabbed = s.hand->grab(s.spec.frameAt(now), now);
      if (!grabbed) {
        return Error{"hands[" + std::to_string(h) + "] '" + s.spec.name +
                     "': grab at t = " + formatNumber(now) + " s: " + grabbed.error().message};
      }
    }
    if (s.hand->grabbed()) {
      if (Status moved = s.hand->moveTo(s.spec.frameAt(now + dt)); !moved) {
        return Error{"hands[" + std::to_string(h) + "] '" + s.spec.name +
                     "': at t = " + formatNumber(now + dt) + " s: " + moved.error().message};
      }
    }
  }
  return Ok{};
}

namespace {

// A manual device without the viewer would hold its tool still for the whole run: refuse it
// with the kinds that can move a tool there.
Status refuseManualDevices(const SceneSpec& spec) {
  for (const RigidBodySpec& r : spec.rigid_bodies) {
    if (!r.device || r.device->kind != DeviceSpec::Kind::kManual) continue;
    return Error{spec.file + ": device 'manual' of tool '" + r.name +
                 "' is moved by the mouse and keys of torsion view, which this run has not: "
                 "use scripted, replay, network, spacemouse or plugin"};
  }
  return Ok{};
}

}  // namespace

Result<std::unique_ptr<BuiltScene>> buildScene(SceneSpec spec, const BuildOptions& options) {
  if (!options.manual_devices) {
    if (Status refused = refuseManualDevices(spec); !refused) return refused.error();
  }
  auto built = std::make_unique<BuiltScene>();
  if (options.threads >= 0) spec.world.solver.threads = options.threads;
  built->world = std::make_unique<FemWorld>(spec.world);
  FemWorld& world = *built->world;
  if (Status contact = world.femSolver().setFemContact(spec.fem_contact); !contact)
    return Error{spec.file + ": fem_contact: " + contact.error().message};

  for (size_t b = 0; b < spec.bodies.size(); ++b) {
    const BodySpec& body = spec.bodies[b];
    const std::string entry = spec.file + ": bodies[" + std::to_string(b) + "] '" + body.name + "'";
    Result<LoadedMesh> mesh = readMesh(body.mesh_path);
    if (!mesh) return Error{entry + ": " + mesh.error().message};
    for (const std::string& w : mesh.value().warnings)
      built->warnings.push_back(w);
    if (Status carried =
            checkStiffnessRatio(body.material, mesh.value().mesh, spec.world.solver.time_step);
        !carried)
      return Error{entry + ": " + carried.error().message};
    Result<FemBody*> added = world.addBody(body.name, mesh.value().mesh, body.material, body.pose,
                                           body.element, body.numbering);
    if (!added) return Error{entry + ": " + added.error().message};
    if (body.linear_velocity != Eigen::Vector3d::Zero() ||
        body.angular_velocity != Eigen::Vector3d::Zero()) {
      if (Status set = added.value()->setRigidVelocity(body.linear_velocity, body.angular_velocity);
          !set)
        return Error{entry + ": " + set.error().message};
    }
    if (body.self_contact) {
      if (Status on = added.value()->enableSelfContact(*body.self_contact); !on)
        return Error{entry + ": " + on.error().message};
    }
  }

  for (size_t s = 0; s < spec.node_sets.size(); ++s) {
    const NodeSetSpec& set = spec.node_sets[s];
    const std::string entry =
        spec.file + ": node_sets[" + std::to_string(s) + "] '" + set.name + "'";
    FemBody* body = world.body(set.body);
    std::vector<int> nodes = selectNodes(body->model().mesh(), set.selection);
    if (nodes.empty()) {
      return Error{entry + ": the selection matches no node of body '" + set.body +
                   "' (check the plane, box or sphere against the mesh bounds)"};
    }
    NodeSetHandle handle;
    handle.name = set.name;
    handle.body = body;
    handle.wrench_about = set.wrench_about;
    handle.node_count = static_cast<int>(nodes.size());
    FrameMotion motion = set.fixed
                             ? FrameMotion([](double) { return Frame{}; })
                             : FrameMotion([m = set.motion](double t) { return m.frameAt(t); });
    handle.group = body->carryNodes(set.name, std::move(nodes), std::move(motion), world.time());
    built->node_sets.push_back(handle);
  }

  for (size_t h = 0; h < spec.hands.size(); ++h) {
    SceneHand scene_hand;
    scene_hand.spec = spec.hands[h];
    scene_hand.hand = std::make_unique<Hand>(*world.body(scene_hand.spec.body),
                                             scene_hand.spec.name, scene_hand.spec.settings);
    built->hands.push_back(std::move(scene_hand));
  }
  // Hands that grab at t = 0 grab now, so a plane that misses is reported before any step.
  for (size_t h = 0; h < built->hands.size(); ++h) {
    if (built->hands[h].spec.grab_at > 0) continue;
    Status grabbed = driveHands(*built);
    if (!grabbed) return Error{spec.file + ": " + grabbed.error().message};
    break;
  }

  for (const RigidBodySpec& r : spec.rigid_bodies)
    built->rigid_bodies.push_back(addSceneRigidBody(world, r));
  if (spec.ground) addSceneRigidBody(world, *spec.ground);
  built->spec = std::move(spec);
  bool devices = false;
  for (const SceneHand& h : built->hands)
    devices = devices || h.spec.device.has_value();
  for (const RigidBodySpec& r : built->spec.rigid_bodies)
    devices = devices || r.isTool();
  if (devices) {
    Result<std::unique_ptr<SceneHaptics>> haptics = SceneHaptics::attach(*built);
    if (!haptics) return Error{built->spec.file + ": " + haptics.error().message};
    built->haptics = std::move(haptics).value();
  }
  return built;
}

}  // namespace torsion::scene
