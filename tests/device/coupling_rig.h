#pragma once
// A cylinder (r = 1, L = 10, base fixed at z = 0), a hand at z = 9.9 and its HandCoupling, fed
// HandCommands directly (no loop thread): the simulation side of the coupling, deterministic.

#include <map>
#include <memory>
#include <string>

#include "torsion/bullet/fem_world.h"
#include "torsion/bullet/hand.h"
#include "torsion/device/pose_math.h"
#include "torsion/haptics/hand_coupling.h"
#include "torsion/mesh/mesh_io.h"

namespace torsion::haptics {

inline const TetMesh& cylinderMesh(int tets) {
  static std::map<int, TetMesh> cache;
  auto it = cache.find(tets);
  if (it == cache.end()) {
    Result<LoadedMesh> loaded =
        readMesh(std::string(TORSION_ASSETS_DIR) + "/cylinder_" + std::to_string(tets) + ".node");
    it = cache.emplace(tets, loaded.ok() ? std::move(loaded).value().mesh : TetMesh()).first;
  }
  return it->second;
}

struct CouplingRig {
  std::unique_ptr<FemWorld> world;
  FemBody* body = nullptr;
  std::unique_ptr<Hand> hand;
  std::unique_ptr<HandCoupling> coupling;
  int base_group = -1;
  device::HandCommand command;
  device::SimulationWrench published;

  CouplingRig(int tets, const SolverSettings& solver, const CouplingSettings& settings = {},
              double mass_damping = 0, ElementKind element = ElementKind::kTet4,
              double youngs_modulus = 1e5, const DeviceMapping* device_mapping = nullptr) {
    WorldSettings ws;
    ws.gravity.setZero();
    ws.solver = solver;
    world = std::make_unique<FemWorld>(ws);
    Material material;  // E = 1e5 Pa (by default), nu = 0.3, rho = 1000, as the twist scenes
    material.youngs_modulus = youngs_modulus;
    material.stiffness_damping = 0.01;
    material.mass_damping = mass_damping;  // 1/s
    body = world->addBody("cylinder", cylinderMesh(tets), material, Frame{}, element).value();
    const TetMesh& mesh = body->model().mesh();  // all nodes (tet10: also the mid-edge ones)
    std::vector<int> base;
    for (int i = 0; i < mesh.nodeCount(); ++i) {
      if (std::abs(mesh.restPositions()[static_cast<size_t>(i)].z()) < 1e-6) base.push_back(i);
    }
    base_group = body->carryNodes(
        "base", base, [](double) { return Frame{}; }, 0);
    hand = std::make_unique<Hand>(*body);
    DeviceMapping mapping = device_mapping ? *device_mapping : DeviceMapping{};
    mapping.anchor.origin = Eigen::Vector3d(0, 0, 9.9);  // the device's zero is the hand plane
    coupling = std::make_unique<HandCoupling>(*hand, mapping, settings);
    command.alive = true;
  }

  /// One step with the device at `pose`; button presses so far as given.
  WorldStepReport step(const device::Pose& pose, std::uint32_t grabs = 1,
                       std::uint32_t releases = 0) {
    ++command.tick;
    command.pose = pose;
    command.grab_requests = grabs;
    command.release_requests = releases;
    Status applied = coupling->apply(command, world->time());
    EXPECT_TRUE(applied.ok()) << (applied.ok() ? "" : applied.error().message);
    WorldStepReport r = world->step();  // not const: returned by move
    EXPECT_TRUE(r.ok) << r.message;
    published = coupling->publish(static_cast<std::uint64_t>(world->stepCount()));
    return r;
  }
};

/// A device pose displaced by `amount` (m or rad) along twist axis `axis` (0-2 translation,
/// 3-5 rotation).
inline device::Pose displaced(int axis, double amount) {
  device::Pose p;
  device::Vec3 v;
  (&v.x)[axis % 3] = amount;
  if (axis < 3) {
    p.position = v;
  } else {
    p.orientation = device::fromRotationVector(v);
  }
  return p;
}

inline double component(const Wrench& w, int axis) {
  return axis < 3 ? w.force[axis] : w.torque[axis - 3];
}

}  // namespace torsion::haptics
