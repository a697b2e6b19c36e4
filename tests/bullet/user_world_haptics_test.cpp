// A haptic device driving a hand on an FEM body in a world the user steps with substeps.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include "torsion/bullet/hand.h"
#include "torsion/device/scripted_device.h"
#include "torsion/haptics/hand_coupling.h"
#include "torsion/haptics/haptic_runtime.h"
#include "torsion/haptics/tool_coupling.h"
#include "torsion/mesh/box_mesh.h"
#include "user_world.h"

namespace torsion {
namespace {

using testing::UserWorld;

TEST(UserWorldHaptics, LockstepLoopTicksThroughEverySubstepAndFeelsThePush) {
  UserWorld user(btVector3(0, 0, 0));
  Material material;
  material.youngs_modulus = 1e5;
  material.mass_damping = 20;  // quasi-static: the reaction has the sign of statics
  FemBody* bar =
      user.fem.addBody("bar", makeBoxTetMesh({0, 0, 0}, {0.4, 0.4, 2}, 2, 2, 8).value(), material)
          .value();
  std::vector<int> base;
  for (int i = 0; i < bar->model().nodeCount(); ++i) {
    if (bar->model().mesh().restPositions()[static_cast<size_t>(i)].z() < 1e-9) base.push_back(i);
  }
  bar->carryNodes(
      "base", base, [](double) { return Frame{}; }, 0.0);
  Hand hand(*bar);
  haptics::DeviceMapping mapping;
  mapping.anchor.origin = Eigen::Vector3d(0.2, 0.2, 1.9);  // the device's zero is the hand plane
  haptics::HandCoupling coupling(hand, mapping, haptics::CouplingSettings{});

  device::Pose pushed;
  pushed.position.x = 0.05;  // m along x, over 0.5 s
  const device::Trajectory push({{0, device::Pose{}}, {0.5, pushed}}, {{0, 1u}});
  device::ScriptedDevice scripted(push, device::defaultDeviceLimits(), "push");
  device::HapticLoopSettings loop_settings;
  loop_settings.log_capacity = 2000;
  device::HapticLoop loop(scripted, loop_settings);
  haptics::HapticRuntime runtime(user.fem, {{&coupling, &loop, 1000}});
  runtime.setLockstep(true);

  for (int call = 0; call < 60; ++call) {
    user.world.stepSimulation(btScalar(1 / 60.), 10, btScalar(1 / 240.));
    ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
  }
  EXPECT_TRUE(hand.grabbed());
  EXPECT_TRUE(runtime.warnings().empty());
  // The loop ticked at 1 kHz on the FEM clock, through the end of the last substep.
  EXPECT_NEAR(static_cast<double>(loop.log().size()), 1000 * user.fem.time(), 1.0);
  // Each substep published its wrench: the ticks leading up to a step render the step before's,
  // so the last tick rendered the last-but-one FEM step.
  EXPECT_EQ(loop.log().back().sim_step, static_cast<std::uint64_t>(user.fem.stepCount() - 1));
  EXPECT_LT(scripted.lastWritten().force.x, -0.1);  // N: the bar resists the push along x
}

TEST(UserWorldHaptics, ATorsionToolInTheUsersWorldPressesThroughEverySubstep) {
  // The user's world under gravity, stepped at 1/60 s with four substeps: a 0.1 kg sphere held
  // by a scripted device goes 5 mm into a static box. Through every substep the coupling moves
  // with Bullet's clock: the device feels the wall's push on the tool, k times the depth plus the
  // tool's weight (its weight compensated, the device feels the contact), and
  // a force the user put on the tool before stepSimulation is still on it (Bullet clears it after
  // the call, not the coupling).
  UserWorld user;
  btRigidBody* wall =
      user.addRigid(std::make_unique<btBoxShape>(btVector3(1, 1, 0.5)), 0, btVector3(0, 0, -0.5));
  (void)wall;
  btRigidBody* tool = user.addRigid(std::make_unique<btSphereShape>(btScalar(0.05)), 0.1,
                                    btVector3(0, 0, btScalar(0.06)));
  haptics::DeviceMapping mapping;
  mapping.anchor.origin = Eigen::Vector3d(0, 0, 0.06);
  haptics::ToolCouplingSettings settings;
  settings.stiffness = 1000;
  std::unique_ptr<haptics::ToolCoupling> coupling =
      haptics::ToolCoupling::create(*tool, user.fem, mapping, settings).value();
  device::Pose pressed;
  pressed.position.z = -0.015;  // 1 cm to the wall, 5 mm into it
  device::ScriptedDevice scripted(device::Trajectory({{0, device::Pose{}}, {0.5, pressed}}, {}),
                                  device::defaultDeviceLimits(), "press");
  device::HapticLoopSettings loop_settings;
  loop_settings.buttons_switch_force = false;
  device::HapticLoop loop(scripted, loop_settings);
  haptics::HapticRuntime runtime(user.fem, {{coupling.get(), &loop, 1000}});
  runtime.setLockstep(true);
  for (int call = 0; call < 60; ++call) {
    tool->applyCentralForce(btVector3(0, 0, 0));  // the user's own forces ride along
    user.world.stepSimulation(btScalar(1 / 60.), 10, btScalar(1 / 240.));
    ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
  }
  EXPECT_EQ(user.fem.stepCount(), 240);
  EXPECT_NEAR(tool->getCenterOfMassPosition().z(), 0.05, 1e-3);  // m: on the wall
  EXPECT_NEAR(coupling->worldWrench().force.z(), 1000 * 0.005 + 0.1 * 9.81, 0.05);
  EXPECT_NEAR(1.0 / tool->getInvMass(), 0.1, 1e-12) << "the tool's own mass between steps";

  // The user's force (10 N up, lifting more than the 5 N press) is applied in each substep.
  for (int call = 0; call < 30; ++call) {
    tool->applyCentralForce(btVector3(0, 0, 10));
    user.world.stepSimulation(btScalar(1 / 60.), 10, btScalar(1 / 240.));
  }
  EXPECT_GT(tool->getCenterOfMassPosition().z(), 0.05 + 1e-3);  // lifted off the wall
  // At rest off the wall the spring balances the user's 10 N (the weight compensated).
  EXPECT_NEAR(coupling->worldWrench().force.z(), 10.0, 0.1);
}

// A bar (0.4 x 0.4 x 2 m, 1 x 1 x 4 cells, E = 1e5 Pa) free in a user's world without gravity,
// its hand coupled to a scripted device that holds still with button 1 pressed, behind a haptic
// loop at 1 kHz: the threaded runtime's rig.
struct HeldBar {
  static haptics::DeviceMapping atTheTop() {
    haptics::DeviceMapping mapping;
    mapping.anchor.origin = Eigen::Vector3d(0.2, 0.2, 1.9);
    return mapping;
  }
  UserWorld user{btVector3(0, 0, 0)};
  FemBody* bar =
      user.fem.addBody("bar", makeBoxTetMesh({0, 0, 0}, {0.4, 0.4, 2}, 1, 1, 4).value(), Material{})
          .value();
  Hand hand{*bar};
  haptics::HandCoupling coupling{hand, atTheTop(), haptics::CouplingSettings{}};
  device::ScriptedDevice scripted{
      device::Trajectory({{0, device::Pose{}}, {10, device::Pose{}}}, {{0, 1u}}),
      device::defaultDeviceLimits(), "hold"};
  device::HapticLoop loop{scripted, device::HapticLoopSettings{}};
  haptics::HapticRuntime runtime{user.fem, {{&coupling, &loop, 1000}}};
};

TEST(UserWorldHaptics, ThreadedLoopRunsBesideTheUsersSteppingLoop) {
  // The haptic loop on its own thread, the user's stepSimulation on this one: they meet only in
  // the lock-free buffers (the ThreadSanitizer build runs this test).
  HeldBar rig;
  rig.runtime.startThreads();
  for (int call = 0; call < 20; ++call) {
    rig.user.world.stepSimulation(btScalar(1 / 60.), 10, btScalar(1 / 240.));
    ASSERT_TRUE(rig.user.fem.status().ok) << rig.user.fem.status().message;
  }
  rig.runtime.stopThreads();
  EXPECT_GT(rig.loop.stats().ticks, 0u);
  EXPECT_TRUE(rig.hand.grabbed()) << "the button pressed on the loop's thread reached the hand";
  EXPECT_EQ(rig.user.fem.stepCount(), 80);
}

TEST(UserWorldHaptics, TheSteppingThreadIsRealTimeOnlyWhileTheLoopsRun) {
  // setSimulationPriority: SCHED_FIFO at startThreads() when the process may have it (the
  // result says which), and the thread's own policy back at stopThreads() either way.
  HeldBar rig;
  int policy_before = -1, policy = -1;
  sched_param before{}, during{};
  ASSERT_EQ(pthread_getschedparam(pthread_self(), &policy_before, &before), 0);
  rig.runtime.setSimulationPriority(40);
  rig.runtime.startThreads();
  ASSERT_EQ(pthread_getschedparam(pthread_self(), &policy, &during), 0);
  if (rig.runtime.simulationRealtime()) {
    EXPECT_EQ(policy, SCHED_FIFO);
    EXPECT_EQ(during.sched_priority, 40);
  } else {
    EXPECT_EQ(policy, policy_before);  // refused: unchanged
  }
  for (int call = 0; call < 5; ++call) {
    rig.user.world.stepSimulation(btScalar(1 / 60.), 10, btScalar(1 / 240.));
    ASSERT_TRUE(rig.user.fem.status().ok) << rig.user.fem.status().message;
  }
  rig.runtime.stopThreads();
  sched_param after{};
  ASSERT_EQ(pthread_getschedparam(pthread_self(), &policy, &after), 0);
  EXPECT_EQ(policy, policy_before);
  EXPECT_EQ(after.sched_priority, before.sched_priority);
  EXPECT_FALSE(rig.runtime.simulationRealtime());
}

}  // namespace
}  // namespace torsion
