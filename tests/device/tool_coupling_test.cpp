// A rigid tool held by a scripted device through the virtual coupling (tool_coupling.h), the
// whole path a scene takes: ScriptedDevice -> HapticLoop (lockstep, 1 kHz) -> HapticRuntime ->
// ToolCoupling -> Bullet's rigid solve and the FEM contact island -> the wrench the loop renders.

#include "torsion/haptics/tool_coupling.h"

#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <limits>
#include <memory>
#include <vector>

#include "arm_device.h"
#include "torsion/bt_conversions.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/device/haptic_loop.h"
#include "torsion/device/scripted_device.h"
#include "torsion/haptics/grasper_coupling.h"
#include "torsion/haptics/haptic_runtime.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion::haptics {
namespace tool_coupling_test {

btTransform at(const Eigen::Vector3d& p) {
  btTransform t;
  t.setIdentity();
  t.setOrigin(toBt(p));
  return t;
}

device::Pose devicePose(double x, double y, double z) {
  device::Pose pose;
  pose.position = {x, y, z};
  return pose;
}

// A scripted device playing `trajectory`, its 1 kHz loop (a tool's: force on from the start)
// and the runtime that ticks it in lockstep with `world`'s steps through `coupling`.
struct ScriptedDeviceLoop {
  std::unique_ptr<device::ScriptedDevice> device;
  std::unique_ptr<device::HapticLoop> loop;
  std::unique_ptr<HapticRuntime> runtime;

  ScriptedDeviceLoop(FemWorld& world, DeviceCoupling& coupling, device::Trajectory trajectory,
                     std::size_t log_capacity = 0) {
    device = std::make_unique<device::ScriptedDevice>(std::move(trajectory),
                                                      device::defaultDeviceLimits(), "tool");
    device::HapticLoopSettings settings;
    settings.buttons_switch_force = false;
    settings.log_capacity = log_capacity;
    loop = std::make_unique<device::HapticLoop>(*device, settings);
    runtime = std::make_unique<HapticRuntime>(
        world, std::vector<HapticBinding>{{&coupling, loop.get(), 1000}});
    runtime->setLockstep(true);
  }
  /// `seconds` of 0.01 s steps; each must succeed.
  void run(double seconds) {
    const int steps = static_cast<int>(std::lround(seconds / 0.01));
    for (int k = 0; k < steps; ++k)
      ASSERT_TRUE(runtime->step().ok) << "step " << k;
  }
};

// A soft slab (0.1 x 0.1 x 0.02 m, base held at z = 0) and a sphere probe (radius 1 cm) held by a
// scripted device whose zero pose is the probe's start, 5 mm above the slab.
struct ProbeRig {
  static constexpr double kRadius = 0.01;     // m
  static constexpr double kProbeMass = 0.02;  // kg
  static constexpr double kTop = 0.02;        // m, the slab's top face
  std::unique_ptr<FemWorld> world;
  FemBody* slab = nullptr;
  int base_group = -1;
  btRigidBody* probe = nullptr;
  std::unique_ptr<ToolCoupling> coupling;
  std::unique_ptr<ScriptedDeviceLoop> link;

  ProbeRig(const std::vector<device::TrajectoryKeyframe>& keyframes, double gravity,
           const ToolCouplingSettings& settings = {}, double friction = 0.5) {
    WorldSettings ws;
    ws.gravity = Eigen::Vector3d(0, 0, -gravity);
    ws.solver.time_step = 0.01;
    ws.solver.threads = 1;
    world = std::make_unique<FemWorld>(ws);
    Material material;
    material.youngs_modulus = 1e5;
    material.poisson_ratio = 0.3;
    material.density = 1000;
    material.stiffness_damping = 0.001;
    slab = world
               ->addBody("slab",
                         makeBoxTetMesh({-0.05, -0.05, 0}, {0.05, 0.05, kTop}, 10, 10, 2).value(),
                         material)
               .value();
    std::vector<int> base;
    for (int i = 0; i < slab->model().nodeCount(); ++i)
      if (slab->state().position(i).z() < 1e-9) base.push_back(i);
    base_group = slab->carryNodes(
        "base", base, [](double) { return Frame{}; }, 0);
    const Eigen::Vector3d start(0, 0, kTop + kRadius + 0.005);
    probe = world->addRigidBody(std::make_unique<btSphereShape>(btScalar(kRadius)), kProbeMass,
                                at(start));
    probe->setFriction(btScalar(friction));
    DeviceMapping mapping;
    mapping.anchor.origin = start;
    coupling = ToolCoupling::create(*probe, world->femSolver(), mapping, settings).value();
    link =
        std::make_unique<ScriptedDeviceLoop>(*world, *coupling, device::Trajectory(keyframes, {}));
  }

  void run(double seconds) { link->run(seconds); }
  Eigen::Vector3d probeCentre() const { return toEigen(probe->getCenterOfMassPosition()); }
  /// The force the slab's base carries (what the body pushes its held base nodes with).
  Eigen::Vector3d baseForce() {
    return slab->groupWrench(base_group, Eigen::Vector3d::Zero()).force;
  }
};

std::vector<device::TrajectoryKeyframe> pressThenHold(double depth) {
  return {{0, devicePose(0, 0, 0)}, {0.5, devicePose(0, 0, -depth)}, {9, devicePose(0, 0, -depth)}};
}

TEST(ToolCoupling, TheDeviceFeelsWhatTheSlabsBaseCarriesAtEquilibrium) {
  // The device goes 8 mm down from the probe's start, 5 mm above the slab, over 0.5 s and
  // holds: the probe indents the slab. At rest the wrench the device renders and the force on the
  // slab's held base are one force (no gravity): the coupling and the contact impulses agree.
  ProbeRig rig(pressThenHold(0.008), 0.0);
  rig.run(3.0);
  const Eigen::Vector3d felt = rig.coupling->worldWrench().force;
  const Eigen::Vector3d base = rig.baseForce();
  ASSERT_GT(felt.z(), 0.5);  // N: pushed back up
  EXPECT_NEAR(felt.z(), -base.z(), 0.01 * felt.z());
  EXPECT_LT((felt + base).norm(), 0.01 * felt.z());
  EXPECT_LT(rig.probeCentre().z(), ProbeRig::kTop + ProbeRig::kRadius);  // m: it indents
  EXPECT_GT(rig.probeCentre().z(), ProbeRig::kTop + ProbeRig::kRadius - 0.003);
}

TEST(ToolCoupling, UnderGravityTheWeightIsCompensatedUnlessFelt) {
  // Under gravity, at rest on the slab: with the weight compensated (the default) the device
  // feels the contact only, the base's force less the slab's own weight; with feel_weight it
  // feels the probe's weight on top.
  for (bool feel_weight : {false, true}) {
    ToolCouplingSettings settings;
    settings.feel_weight = feel_weight;
    ProbeRig rig(pressThenHold(0.008), 9.81, settings);
    rig.run(3.0);
    // The held base carries the weight of the nodes above it (its own nodes' weight is not an
    // elastic force) and the probe's push.
    double carried_mass = 0;
    for (int i = 0; i < rig.slab->model().nodeCount(); ++i) {
      if (rig.slab->model().mesh().restPositions()[static_cast<size_t>(i)].z() > 1e-9)
        carried_mass += rig.slab->model().nodeMasses()[static_cast<size_t>(i)];
    }
    const double contact = -rig.baseForce().z() - 9.81 * carried_mass;  // N, the probe's push
    const double weight = 9.81 * ProbeRig::kProbeMass;
    ASSERT_GT(contact, 0.5);
    EXPECT_NEAR(rig.coupling->worldWrench().force.z(), contact - (feel_weight ? weight : 0),
                0.01 * contact)
        << (feel_weight ? "weight felt" : "weight compensated");
  }
}

TEST(ToolCoupling, SlidingOverTheSlabTheDeviceFeelsMuTimesTheNormalForce) {
  // Pressed in, then dragged 3 cm sideways at 1 cm/s at a constant device height: the probe
  // slides (the coupling holds its orientation), and the device feels Coulomb's law, the
  // tangential force mu times the normal one. Both are averaged over the last two centimetres,
  // two whole cells of the mesh: over one cell the ratio swings by a quarter either way as the
  // contact patch (about 5 mm across) crosses the 1 cm grid of surface nodes. The drag of the
  // frictionless probe (the slab's damping and its surface pushed ahead) is measured apart.
  auto slidingRatio = [](double mu) {
    ProbeRig rig({{0, devicePose(0, 0, 0)},
                  {0.5, devicePose(0, 0, -0.0075)},
                  {1.0, devicePose(0, 0, -0.0075)},
                  {4.0, devicePose(0.03, 0, -0.0075)}},
                 0.0, {}, mu);
    rig.run(2.0);  // pressed, then the first centimetre: sliding under way
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int k = 0; k < 200; ++k) {
      rig.run(0.01);
      sum += rig.coupling->worldWrench().force;
    }
    EXPECT_GT(rig.probeCentre().x(), 0.028);  // m: it followed the device
    EXPECT_GT(sum.z(), 0);
    EXPECT_LT(std::abs(sum.y()), 1e-3 * sum.z());
    return -sum.x() / sum.z();
  };
  constexpr double kMu = 0.4;  // the probe's friction (the slab's is 1)
  const double with_friction = slidingRatio(kMu);
  const double drag = slidingRatio(0.0);
  EXPECT_NEAR(with_friction, kMu, 0.05 * kMu);
  EXPECT_LT(drag, 0.02);
  EXPECT_NEAR(with_friction - drag, kMu, 0.01 * kMu);
}

TEST(ToolCoupling, OnASoftBodyTheLocalModelIsTheCouplingInSeriesWithThePatch) {
  // Pressed into the slab and at rest, the probe publishes K_h = -(k k_e / (k + k_e)) along the
  // push, k_e the contact patch's stiffness from the slab's step system (contact_stiffness.h).
  // Against it: the secant stiffness between two rests 0.5 mm of device travel apart, the force
  // change over the probe's depth change (measured: K_h within 2.2 % of the series; the secant
  // of a contact that stiffens as it deepens is not the tangent at the first rest, hence 10 %).
  ProbeRig rig({{0, devicePose(0, 0, 0)},
                {0.5, devicePose(0, 0, -0.008)},
                {2.0, devicePose(0, 0, -0.008)},
                {2.5, devicePose(0, 0, -0.0085)},
                {9, devicePose(0, 0, -0.0085)}},
               0.0);
  rig.run(2.0);
  const double f1 = rig.coupling->worldWrench().force.z(), z1 = rig.probeCentre().z();
  const double k_h = rig.coupling->worldStiffness()(2, 2);
  rig.run(2.0);
  const double f2 = rig.coupling->worldWrench().force.z(), z2 = rig.probeCentre().z();
  const double secant = (f2 - f1) / (z1 - z2);  // N/m of the slab's contact
  const double k = ToolCouplingSettings{}.stiffness;
  const double expected = -k * secant / (k + secant);
  ASSERT_GT(secant, 0);
  EXPECT_NEAR(k_h, expected, 0.1 * std::abs(expected));
  EXPECT_LT(std::abs(rig.coupling->worldStiffness()(0, 0)), 0.05 * std::abs(k_h));  // sideways
}

// The probe 5 mm above a static rigid box (its top at z = 0), the device's zero pose at the
// probe's start; the loop logs every tick.
struct WallRig {
  static constexpr double kRadius = 0.01;     // m
  static constexpr double kStiffness = 1000;  // N/m, the coupling's
  std::unique_ptr<FemWorld> world;
  btRigidBody* probe = nullptr;
  std::unique_ptr<ToolCoupling> coupling;
  std::unique_ptr<ScriptedDeviceLoop> link;

  explicit WallRig(const std::vector<device::TrajectoryKeyframe>& keyframes) {
    WorldSettings ws;
    ws.gravity.setZero();
    ws.solver.time_step = 0.01;
    world = std::make_unique<FemWorld>(ws);
    world->addRigidBody(std::make_unique<btBoxShape>(btVector3(0.1, 0.1, 0.05)), 0,
                        at({0, 0, -0.05}));
    const Eigen::Vector3d start(0, 0, kRadius + 0.005);
    probe =
        world->addRigidBody(std::make_unique<btSphereShape>(btScalar(kRadius)), 0.02, at(start));
    DeviceMapping mapping;
    mapping.anchor.origin = start;
    ToolCouplingSettings settings;
    settings.stiffness = kStiffness;
    coupling = ToolCoupling::create(*probe, world->femSolver(), mapping, settings).value();
    link = std::make_unique<ScriptedDeviceLoop>(*world, *coupling,
                                                device::Trajectory(keyframes, {}), 10000);
  }
  void run(double seconds) { link->run(seconds); }
};

TEST(ToolCoupling, ARigidWallFeelsAsStiffAsTheCouplingAtTheLoopsRate) {
  // The device goes 1 cm down at 1 cm/s, 5 mm into the wall, holds 0.5 s and comes back. The
  // probe stops at the wall; between steps the loop predicts with K_h = -k along the wall's
  // normal, so each tick's force is the coupling's k times the device's depth in the wall, not
  // a 100 Hz staircase (whose steps would be k v dt = 0.1 N). The port stays passive.
  WallRig rig({{0, devicePose(0, 0, 0)},
               {1.0, devicePose(0, 0, -0.01)},
               {1.5, devicePose(0, 0, -0.01)},
               {2.5, devicePose(0, 0, 0)}});
  rig.run(1.2);
  const Matrix6d& k_h = rig.coupling->worldStiffness();
  EXPECT_NEAR(k_h(2, 2), -WallRig::kStiffness, 0.01 * WallRig::kStiffness);
  EXPECT_LT(std::abs(k_h(0, 0)), 1e-3 * WallRig::kStiffness);  // slides freely sideways
  EXPECT_LT(std::abs(k_h(1, 1)), 1e-3 * WallRig::kStiffness);
  const double sink = WallRig::kRadius - toEigen(rig.probe->getCenterOfMassPosition()).z();
  std::printf("probe sinks %.3g mm\n", 1e3 * sink);
  EXPECT_LT(sink, 5e-4);  // m, Bullet's contact slop and the step's
  // The coupling's damper, b = 2 sqrt(k m) (critical), adds b v while the device moves on.
  const double damper = 2 * std::sqrt(WallRig::kStiffness * 0.02);  // N s/m
  EXPECT_NEAR(rig.coupling->worldWrench().force.z(), WallRig::kStiffness * 0.005, 1e-3);
  rig.run(1.6);

  // Each tick of the press (device 1-5 mm into the wall, t in [0.6, 1.0] s): the rendered force
  // against k times the depth then.
  double worst = 0;
  for (const device::LoopLogRow& row : rig.link->loop->log()) {
    if (row.time < 0.6 || row.time > 1.0) continue;
    const double depth = -0.005 - row.pose.position.z;  // m, the device below the wall's contact
    const double ideal = WallRig::kStiffness * depth + damper * 0.01;  // N, at 1 cm/s
    worst = std::max(worst, std::abs(row.output.force.z - ideal));
  }
  EXPECT_LT(worst, 0.02);  // N, a fifth of a step's staircase
  // Passive: the port gives back at most 1 % of the 12.5 mJ the coupling held at 5 mm.
  EXPECT_LE(rig.link->loop->stats().max_port_energy.load(), 1.25e-4);
}

// Between the solver and the loop: the coupling's stages at the solver's moments, its wrench
// reaching the loop `delay` after the step that made it (a slow or remote simulation).
struct DelayedToolLink : StepListener {
  ToolCoupling& coupling;
  device::HapticLoop& loop;
  double delay;
  std::deque<std::pair<double, device::SimulationWrench>> in_flight;
  DelayedToolLink(ToolCoupling& c, device::HapticLoop& l, double d)
      : coupling(c), loop(l), delay(d) {}
  void beforeRigidStep(const StepContext& ctx) override {
    device::HandCommand command;
    loop.commands().read(command);
    coupling.beforeRigidStep(command, ctx);
  }
  void afterFemStep(const StepContext& ctx, bool ok) override {
    coupling.afterFemStep(ctx, ok);
    if (ok)
      in_flight.emplace_back(ctx.endTime() + delay,
                             coupling.publish(static_cast<std::uint64_t>(ctx.index)));
  }
  void tick(double now) {
    while (!in_flight.empty() && in_flight.front().first <= now + 1e-9) {
      loop.wrenches().write(in_flight.front().second);
      in_flight.pop_front();
    }
    loop.tick(now);
  }
};

TEST(ToolCoupling, AnOperatorPushingIntoARigidWallStaysPassiveAndShallowEvenUnderDelay) {
  // A simulated operator (arm 300 N/m toward an intent 4 cm past the wall, 1 kg; device 0.3 kg,
  // 200 Hz motors, 10 N) pushes the probe into a rigid wall 1 cm away, closing at 5 cm/s, and
  // holds; the simulation's wrench reaches the loop 0 or 20 ms after its step. At rest the
  // operator and the coupling share the push: the device sits k_arm 4 cm / (k_arm + k) = 9.2 mm
  // past the wall, feeling 9.2 N. The device never goes more than a fifth deeper than that, the
  // port gives back at most 1 % of the 42 mJ the coupling then holds, and the motion settles.
  for (double delay : {0.0, 0.02}) {
    SCOPED_TRACE(delay);
    WorldSettings ws;
    ws.gravity.setZero();
    ws.solver.time_step = 0.01;
    FemWorld world(ws);
    world.addRigidBody(std::make_unique<btBoxShape>(btVector3(0.05, 0.1, 0.1)), 0,
                       at({0.02 + 0.05, 0, 0}));
    btRigidBody* probe =
        world.addRigidBody(std::make_unique<btSphereShape>(btScalar(0.01)), 0.02, at({0, 0, 0}));
    ToolCouplingSettings settings;
    settings.stiffness = 1000;
    auto coupling =
        ToolCoupling::create(*probe, world.femSolver(), DeviceMapping{}, settings).value();
    simulated::SimulatedArmSettings arm;
    arm.intent = simulated::SimulatedArmSettings::Intent::kPush;
    arm.intent_rate = 0.05;
    arm.intent_start = 0.1;
    arm.intent_time = 1.0;
    arm.grab_time = -1;
    device::ArmDevice device(arm);
    device::HapticLoopSettings loop_settings;
    loop_settings.buttons_switch_force = false;
    loop_settings.log_capacity = 3100;
    device::HapticLoop loop(device, loop_settings);
    DelayedToolLink link(*coupling, loop, delay);
    world.femSolver().addStepListener(&link);
    int tick = 0;
    while (world.time() < 3.0 - 1e-9) {
      for (int k = 0; k < 10; ++k, ++tick)
        link.tick(tick * 1e-3);
      ASSERT_TRUE(world.step().ok);
    }
    world.femSolver().removeStepListener(&link);
    const double settled = 300 * 0.04 / (300 + 1000);  // m past the wall
    double deepest = 0, late_swing_lo = 1e9, late_swing_hi = -1e9;
    for (const device::LoopLogRow& row : loop.log()) {
      const double past_wall = row.pose.position.x - 0.01;
      deepest = std::max(deepest, past_wall);
      if (row.time > 2.5) {
        late_swing_lo = std::min(late_swing_lo, past_wall);
        late_swing_hi = std::max(late_swing_hi, past_wall);
      }
    }
    std::printf("delay %.0f ms: deepest %.2f mm (settled %.2f), late swing %.3f mm, port %.3g J\n",
                1e3 * delay, 1e3 * deepest, 1e3 * settled, 1e3 * (late_swing_hi - late_swing_lo),
                loop.stats().max_port_energy.load());
    EXPECT_NEAR(toEigen(probe->getCenterOfMassPosition()).x(), 0.01, 5e-4);  // on the wall
    EXPECT_LT(deepest, 1.2 * settled);
    EXPECT_NEAR(late_swing_lo, settled, 0.1 * settled);
    EXPECT_LT(late_swing_hi - late_swing_lo, 0.05 * settled);
    EXPECT_LE(loop.stats().max_port_energy.load(), 0.01 * 0.5 * 1000 * settled * settled);
  }
}

TEST(ToolCoupling, ADeviceLostMidPressFadesToZeroWithoutAJumpAndTheToolHolds) {
  // The device dies 5 mm deep in the wall: the loop fades its output to zero within fade_time
  // (0.2 s) at the filter's rate limit, and the tool stays where the last goal held it.
  WallRig rig(
      {{0, devicePose(0, 0, 0)}, {1.0, devicePose(0, 0, -0.01)}, {3, devicePose(0, 0, -0.01)}});
  rig.link->device->dieAt(1.2);
  rig.run(2.0);
  const device::SafetySettings safety;
  double largest_change = 0, output_at_death = -1;
  device::Wrench previous;
  for (const device::LoopLogRow& row : rig.link->loop->log()) {
    largest_change = std::max(largest_change, std::abs(row.output.force.z - previous.force.z));
    previous = row.output;
    if (output_at_death < 0 && row.time >= 1.2) output_at_death = row.output.force.z;
    if (row.time >= 1.2 + safety.fade_time + 0.002) {
      EXPECT_EQ(row.output.force.z, 0.0) << "t = " << row.time;
    }
  }
  EXPECT_GT(output_at_death, 4.0);                                  // N: it was pressing
  EXPECT_LE(largest_change, safety.max_force_rate * 0.001 + 1e-9);  // N per tick: no jump
  EXPECT_NEAR(toEigen(rig.probe->getCenterOfMassPosition()).z(), WallRig::kRadius, 5e-4);
  EXPECT_NEAR(rig.coupling->worldWrench().force.z(), 5.0, 1e-3);  // the last goal still held
}

TEST(ToolCoupling, AJammedToolIsPushedWithAtMostMaxForceAndTheDeviceAtItsLimit) {
  // The device goes 1 m into the wall: the spring would pull with 1000 N; capped at max_force
  // (100 N) the probe stays on the wall, and the device renders at most its own limit (30 N).
  WallRig rig(
      {{0, devicePose(0, 0, 0)}, {1.0, devicePose(0, 0, -1.0)}, {3, devicePose(0, 0, -1.0)}});
  rig.run(2.0);
  EXPECT_NEAR(rig.coupling->couplingWrench().force.z(), -100.0, 1e-6);
  EXPECT_NEAR(toEigen(rig.probe->getCenterOfMassPosition()).z(), WallRig::kRadius, 5e-4);
  for (const device::LoopLogRow& row : rig.link->loop->log()) {
    ASSERT_LE(std::hypot(row.output.force.x, row.output.force.y, row.output.force.z),
              device::defaultDeviceLimits().max_force + 1e-9);
  }
  EXPECT_NEAR(rig.link->loop->lastOutput().force.z, device::defaultDeviceLimits().max_force, 1e-9);
}

TEST(ToolCoupling, AStiffCouplingOnALightToolIsStableInFreeSpace) {
  // k = 1e6 N/m on a 20 g probe at dt = 0.01 s: k dt^2 / m = 5000, far past any explicit
  // spring's limit. Integrated with the tool, it follows a device that jerks 5 cm sideways in
  // one step without overshoot, and feels nothing once they move together.
  ProbeRig rig({{0, devicePose(0, 0, 0)},
                {0.5, devicePose(0, 0, 0)},
                {0.51, devicePose(0.05, 0, 0.01)},
                {2, devicePose(0.05, 0, 0.01)}},
               9.81, [] {
                 ToolCouplingSettings s;
                 s.stiffness = 1e6;
                 s.max_force = 1e6;
                 return s;
               }());
  double overshoot = 0;
  for (int k = 0; k < 150; ++k) {
    rig.run(0.01);
    overshoot = std::max(overshoot, rig.probeCentre().x() - 0.05);
  }
  EXPECT_LT(overshoot, 1e-4);  // m
  EXPECT_NEAR(rig.probeCentre().x(), 0.05, 1e-5);
  EXPECT_LT(rig.coupling->worldWrench().force.norm(), 1e-3);  // N: weight compensated, at rest
}

TEST(ToolCoupling, APoseOutOfReachOrNotFiniteIsRefusedAndTheLastGoalHeld) {
  WallRig rig({{0, devicePose(0, 0, 0)}});
  const Eigen::Vector3d held = rig.coupling->goal().origin;
  StepContext ctx;
  ctx.dt = 0.01;
  device::HandCommand command;
  command.tick = 1;
  command.alive = true;
  for (double x : {1.7e308, std::numeric_limits<double>::quiet_NaN()}) {
    command.pose.position.x = x;
    rig.coupling->beforeRigidStep(command, ctx);
    rig.coupling->afterFemStep(ctx, true);
  }
  EXPECT_EQ(rig.coupling->rejectedPoses(), 2u);
  EXPECT_EQ(rig.coupling->goal().origin, held);
  EXPECT_NEAR(1.0 / toDouble(rig.probe->getInvMass()), 0.02, 1e-12) << "its own mass back";
}

TEST(ToolCoupling, OnlyADynamicBodyWithValidSettingsCanBeATool) {
  WallRig rig({{0, devicePose(0, 0, 0)}});
  btRigidBody* wall = rig.world->rigidBodies().front();
  Result<std::unique_ptr<ToolCoupling>> fixed =
      ToolCoupling::create(*wall, rig.world->femSolver(), DeviceMapping{}, ToolCouplingSettings{});
  ASSERT_FALSE(fixed.ok());
  EXPECT_NE(fixed.error().message.find("dynamic"), std::string::npos) << fixed.error().message;
  ToolCouplingSettings bad;
  bad.stiffness = -1;
  Result<std::unique_ptr<ToolCoupling>> refused =
      ToolCoupling::create(*rig.probe, rig.world->femSolver(), DeviceMapping{}, bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("stiffness"), std::string::npos);
}

// A soft block (0.1 m cube, E 5e4 Pa, 0.2 kg) on the ground and a grasper above it: a palm
// (0.5 kg) with two jaws (0.1 kg, 2 x 8 x 8 cm) 14 cm apart, on a scripted device that lowers
// it 0.1 m over 1 s, holds button 1 from 1.2 s, lifts 0.15 m over 1 s from 2 s and holds.
struct GraspRig {
  std::unique_ptr<FemWorld> world;
  FemBody* block = nullptr;
  btRigidBody* palm = nullptr;
  std::array<btRigidBody*, 2> jaws{};
  std::unique_ptr<GrasperCoupling> grasper;
  std::unique_ptr<ScriptedDeviceLoop> link;

  GraspRig() {
    WorldSettings ws;
    ws.solver.time_step = 0.01;
    ws.solver.threads = 1;
    world = std::make_unique<FemWorld>(ws);
    btRigidBody* ground = world->addRigidBody(
        std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), 0), 0, at({0, 0, 0}));
    ground->setFriction(0.5);
    Material material;
    material.youngs_modulus = 5e4;
    material.density = 200;
    material.mass_damping = 1;
    material.stiffness_damping = 0.01;
    block = world
                ->addBody("block",
                          makeBoxTetMesh({-0.05, -0.05, 0}, {0.05, 0.05, 0.1}, 4, 4, 4).value(),
                          material)
                .value();
    const Eigen::Vector3d palm_at(0, 0, 0.24);
    palm = world->addRigidBody(std::make_unique<btBoxShape>(btVector3(0.1, 0.04, 0.01)), 0.5,
                               at(palm_at));
    for (int side : {0, 1}) {
      const double x = (side == 0 ? -1 : 1) * (0.07 + 0.01);
      jaws[static_cast<size_t>(side)] =
          world->addRigidBody(std::make_unique<btBoxShape>(btVector3(0.01, 0.04, 0.04)), 0.1,
                              at(palm_at + Eigen::Vector3d(x, 0, -0.05)));
      jaws[static_cast<size_t>(side)]->setFriction(0.8);
    }
    DeviceMapping mapping;
    mapping.anchor.origin = palm_at;
    ToolCouplingSettings coupling;
    coupling.stiffness = 2000;
    coupling.angular_stiffness = 50;
    GrasperSettings settings;
    settings.opening = 0.14;
    settings.grip_force = 20;
    grasper = GrasperCoupling::create(world->femSolver(), *palm, jaws, mapping, coupling, settings)
                  .value();
    link = std::make_unique<ScriptedDeviceLoop>(*world, *grasper,
                                                device::Trajectory({{0, devicePose(0, 0, 0)},
                                                                    {1.0, devicePose(0, 0, -0.1)},
                                                                    {2.0, devicePose(0, 0, -0.1)},
                                                                    {3.0, devicePose(0, 0, 0.05)},
                                                                    {20, devicePose(0, 0, 0.05)}},
                                                                   {{0, 0u}, {1.2, 1u}}));
  }
  void run(double seconds) { link->run(seconds); }
  Eigen::Vector3d blockCentre() const {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    double m = 0;
    for (int i = 0; i < block->model().nodeCount(); ++i) {
      c += block->model().nodeMasses()[static_cast<size_t>(i)] * block->state().position(i);
      m += block->model().nodeMasses()[static_cast<size_t>(i)];
    }
    return c / m;
  }
  Eigen::Vector3d palmCentre() const { return toEigen(palm->getCenterOfMassPosition()); }
};

TEST(GrasperCoupling, LiftsASoftBlockByFrictionAndHoldsIt5sWithoutSlipping) {
  GraspRig rig;
  rig.run(1.1);
  EXPECT_FALSE(rig.grasper->closing());
  EXPECT_NEAR(rig.grasper->gap(), 0.14, 1e-3);  // m: open
  rig.run(0.9);                                 // closed on the block
  EXPECT_TRUE(rig.grasper->closing());
  EXPECT_LT(rig.grasper->gap(), 0.1);  // m: squeezing the 0.1 m block
  rig.run(1.5);                        // lifted 0.15 m
  const double lifted = rig.blockCentre().z() - 0.05;
  std::printf("block lifted %.4f m, gap %.4f m, felt %.3f N\n", lifted, rig.grasper->gap(),
              rig.grasper->palm().worldWrench().force.z());
  ASSERT_GT(lifted, 0.12);
  const Eigen::Vector3d held = rig.blockCentre() - rig.palmCentre();
  rig.run(5.0);
  const double slip = (rig.blockCentre() - rig.palmCentre() - held).norm();
  std::printf("slip over 5 s: %.3g mm\n", 1e3 * slip);
  EXPECT_LT(slip, 1e-3);  // m
  // The device feels the block's weight (the grasper's own compensated), pulling down.
  double block_mass = 0;
  for (double m : rig.block->model().nodeMasses())
    block_mass += m;
  EXPECT_NEAR(rig.grasper->palm().worldWrench().force.z(), -9.81 * block_mass,
              0.02 * 9.81 * block_mass);
}

// Hertz's force for a rigid sphere (radius r) pressed `depth` into an elastic layer of
// thickness h bonded to a rigid base, frictionless: F = 4/3 E/(1 - nu^2) sqrt(r) d^1.5 times the
// finite-thickness correction of Dimitriadis et al. (2002), a polynomial in chi = sqrt(r d) / h.
double hertzOnBondedLayer(double e, double nu, double r, double depth, double h) {
  const double pi = 3.14159265358979323846;
  const double alpha = -(1.2876 - 1.4678 * nu + 1.3442 * nu * nu) / (1 - nu);
  const double beta = (0.6387 - 1.0277 * nu + 1.5164 * nu * nu) / (1 - nu);
  const double chi = std::sqrt(r * depth) / h;
  const double correction =
      1 - 2 * alpha / pi * chi + 4 * alpha * alpha / (pi * pi) * chi * chi -
      8 / (pi * pi * pi) * (alpha * alpha * alpha + 4 * pi * pi * beta / 15) * chi * chi * chi +
      16 * alpha / (pi * pi * pi * pi) * (alpha * alpha * alpha + 3 * pi * pi * beta / 5) *
          std::pow(chi, 4);
  return 4.0 / 3.0 * e / (1 - nu * nu) * std::sqrt(r) * std::pow(depth, 1.5) * correction;
}

TEST(ToolCoupling, IndentationFollowsHertzOnAFiniteLayer) {
  // A frictionless sphere probe (r = 1 cm) pressed by its device into a soft layer (E 1e4 Pa,
  // nu 0.3, 1 cm thick, 4 x 4 cm, base held) at 0.57 mm/s: the force the device renders
  // against the probe's depth at 1.28 and 1.44 mm (chi = sqrt(r d) / h 0.36 and 0.38), within
  // 5 % of Hertz on the bonded layer; the device's force and the base's are one force (1 %).
  // The mesh, 27 x 27 x 10 cells of 1.5 x 1.5 x 1 mm (43740 tets), puts 2.5 cells across the
  // contact radius: shallower, fewer nodes carry the contact and the error grows (+4.7 % at
  // 1.12 mm, +19 % at 0.3 mm; on a 6 x 6 cm layer of 40 x 40 x 10 cells +7.0, +2.6 and +0.6 % at
  // 1.12, 1.28 and 1.44 mm). docs/validation-contact.md, "Tools".
  constexpr double kE = 1e4, kNu = 0.3, kR = 0.01, kH = 0.01, kHalf = 0.02;
  WorldSettings ws;
  ws.gravity.setZero();
  ws.solver.time_step = 0.01;
  ws.solver.threads = 2;
  ws.solver.tolerance = 1e-6;
  FemWorld world(ws);
  Material material;
  material.youngs_modulus = kE;
  material.poisson_ratio = kNu;
  material.density = 1000;
  material.stiffness_damping = 0.01;
  material.mass_damping = 5;  // 1/s: quasi-static
  FemBody* slab =
      world
          .addBody("slab",
                   makeBoxTetMesh({-kHalf, -kHalf, 0}, {kHalf, kHalf, kH}, 27, 27, 10).value(),
                   material)
          .value();
  std::vector<int> base;
  for (int i = 0; i < slab->model().nodeCount(); ++i)
    if (slab->state().position(i).z() < 1e-9) base.push_back(i);
  const int base_group = slab->carryNodes(
      "base", base, [](double) { return Frame{}; }, 0);
  const Eigen::Vector3d start(0, 0, kH + kR + 0.0002);
  btRigidBody* probe =
      world.addRigidBody(std::make_unique<btSphereShape>(btScalar(kR)), 0.01, at(start));
  probe->setFriction(0);
  DeviceMapping mapping;
  mapping.anchor.origin = start;
  ToolCouplingSettings settings;
  settings.stiffness = 2000;
  auto coupling = ToolCoupling::create(*probe, world.femSolver(), mapping, settings).value();
  ScriptedDeviceLoop link(
      world, *coupling,
      device::Trajectory({{0, devicePose(0, 0, 0)}, {3.0, devicePose(0, 0, -0.0017)}}, {}));
  int checked = 0;
  for (int k = 0; k < 300; ++k) {
    ASSERT_TRUE(link.runtime->step().ok);
    if (k < 269 || k % 30 != 29) continue;  // 2.7 and 3 s: depths 1.28 and 1.44 mm
    const double depth = kH + kR - toEigen(probe->getCenterOfMassPosition()).z();
    const double felt = coupling->worldWrench().force.z();
    const double base_force = -slab->groupWrench(base_group, Eigen::Vector3d::Zero()).force.z();
    const double hertz = hertzOnBondedLayer(kE, kNu, kR, depth, kH);
    std::printf("depth %.3f mm: device %.5f N, base %.5f N, Hertz %.5f N (%+.1f %%)\n", 1e3 * depth,
                felt, base_force, hertz, 100 * (felt / hertz - 1));
    EXPECT_NEAR(felt, hertz, 0.05 * hertz) << "depth " << depth;
    EXPECT_NEAR(felt, base_force, 0.01 * felt);
    ++checked;
  }
  EXPECT_EQ(checked, 2);
}

}  // namespace tool_coupling_test
}  // namespace torsion::haptics
