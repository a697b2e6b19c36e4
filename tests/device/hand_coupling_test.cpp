#include "torsion/haptics/hand_coupling.h"

#include <gtest/gtest.h>

#include <cstdio>

#include "coupling_rig.h"
#include "torsion/device/scripted_device.h"
#include "torsion/haptics/haptic_runtime.h"

// The simulation side of the coupling on the 2430-tet cylinder (unit: a few hundred small steps).
namespace torsion::haptics {
namespace {

SolverSettings quasiStatic() {
  // Steps far longer than the slowest mode (bending, about 36 s for this soft cylinder) with a
  // direct solve: backward Euler becomes a Newton iteration on statics.
  SolverSettings s;
  s.time_step = 1000.0;
  s.linear_solver = LinearSolverKind::kCholmod;
  return s;
}

TEST(HandCoupling, ZeroAtRestAndAfterRelease) {
  CouplingRig rig(2430, quasiStatic());
  rig.step(device::Pose{});
  ASSERT_TRUE(rig.published.grabbed);
  for (int k = 0; k < 2; ++k)
    rig.step(device::Pose{});
  EXPECT_LT(rig.coupling->worldWrench().force.norm(), 1e-6);  // N; rest state: no strain
  EXPECT_LT(rig.coupling->worldWrench().torque.norm(), 1e-6);
  for (int k = 0; k < 3; ++k)
    rig.step(displaced(0, 0.2));
  ASSERT_GT(rig.coupling->worldWrench().force.norm(), 1.0);
  rig.step(displaced(0, 0.2), 1, 1);  // button 2
  EXPECT_FALSE(rig.published.grabbed);
  EXPECT_FALSE(rig.hand->grabbed());
  EXPECT_EQ(rig.coupling->worldWrench().force.norm(), 0.0);
  EXPECT_EQ(rig.published.wrench.force.x, 0.0);
  EXPECT_EQ(rig.published.stiffness[0], 0.0);
}

TEST(HandCoupling, AnEnormousPoseIsDroppedAndCountedNotFollowed) {
  // 1.7e308 m is a finite double and passes the packet check; scaled by the mapping it would
  // overflow, and unscaled it would drag the hand out of the arithmetic's range.
  CouplingRig rig(2430, quasiStatic());
  rig.step(device::Pose{});
  ASSERT_TRUE(rig.published.grabbed);
  const Eigen::Vector3d held = rig.coupling->goal().origin;
  device::Pose wild;
  wild.position.x = 1.7e308;
  rig.step(wild);
  EXPECT_EQ(rig.coupling->rejectedPoses(), 1u);
  EXPECT_EQ(rig.coupling->goal().origin, held);  // the last good goal is held
  EXPECT_TRUE(rig.hand->grabbed());
  EXPECT_TRUE(std::isfinite(rig.coupling->worldWrench().force.norm()));
  rig.step(displaced(0, 0.01));  // good poses are followed again
  EXPECT_EQ(rig.coupling->rejectedPoses(), 1u);
  EXPECT_NEAR(rig.coupling->goal().origin.x(), held.x() + 0.01, 1e-12);
}

TEST(HandCoupling, WrenchOpposesTheDisplacementOnEveryAxis) {
  for (Rendering rendering : {Rendering::kInternalForce, Rendering::kFrameDifference}) {
    for (int axis = 0; axis < 6; ++axis) {
      CouplingSettings settings;
      settings.rendering = rendering;
      settings.stiffness_refresh_steps = 0;  // not needed here
      CouplingRig rig(2430, quasiStatic(), settings);
      rig.step(device::Pose{});
      for (double sign : {1.0, -1.0}) {
        const double amount = sign * (axis < 3 ? 0.1 : 0.05);  // m or rad
        for (int k = 0; k < 3; ++k)
          rig.step(displaced(axis, amount));
        const double w = component(rig.coupling->worldWrench(), axis);
        EXPECT_LT(w * sign, 0) << toString(rendering) << " axis " << axis << " sign " << sign;
        EXPECT_GT(std::abs(w), 1e-2) << toString(rendering) << " axis " << axis;
      }
    }
  }
}

TEST(HandCoupling, LocalStiffnessMatchesAFiniteDifferenceOfTheSimulatedWrench) {
  // Twist the cylinder dynamically (dt = 0.01), pause, and compare K_h with what one more
  // simulated step gives for a small pose change along each axis, from identical replicas.
  SolverSettings dynamic;
  dynamic.tolerance = 1e-8;  // the difference of two solves must not drown in CG noise
  dynamic.max_iterations = 2000;
  auto history = [](int k) { return displaced(5, 0.1 * std::min(k, 10) / 10.0); };
  constexpr int kSteps = 15;
  auto replay = [&](CouplingRig& rig) {
    for (int k = 0; k <= kSteps; ++k)
      rig.step(history(k));
  };
  CouplingSettings settings;
  settings.stiffness_refresh_steps = 1;
  settings.stiffness_columns_per_step = 6;  // all six from the paused state
  settings.stiffness_tolerance = 1e-8;
  CouplingRig reference(2430, dynamic, settings);
  replay(reference);
  const Matrix6d k_h = reference.coupling->worldStiffness();  // paused here
  reference.step(history(kSteps + 1));
  const Wrench w0 = reference.coupling->worldWrench();

  constexpr double kDelta = 1e-4;  // m or rad
  Matrix6d finite_difference;
  for (int axis = 0; axis < 6; ++axis) {
    CouplingRig rig(2430, dynamic, settings);
    replay(rig);
    device::Pose p = history(kSteps + 1);
    double twist[6] = {};
    twist[axis] = kDelta;
    p.position = p.position + device::Vec3{twist[0], twist[1], twist[2]};
    p.orientation = device::fromRotationVector({twist[3], twist[4], twist[5]}) * p.orientation;
    rig.step(p);
    const Wrench w = rig.coupling->worldWrench();
    finite_difference.col(axis) << (w.force - w0.force) / kDelta, (w.torque - w0.torque) / kDelta;
  }
  // Column by column: the force-per-translation and torque-per-rotation blocks carry different
  // units, so each column is compared on its own scale.
  for (int axis = 0; axis < 6; ++axis) {
    const double error = (k_h.col(axis) - finite_difference.col(axis)).norm();
    EXPECT_LT(error, 0.1 * finite_difference.col(axis).norm())
        << "axis " << axis << "\nK_h:\n"
        << k_h.col(axis).transpose() << "\nfinite difference:\n"
        << finite_difference.col(axis).transpose();
  }
}

TEST(HandCoupling, PublishesInTheDeviceFrame) {
  CouplingSettings settings;
  settings.rendering = Rendering::kFrameDifference;
  CouplingRig rig(2430, quasiStatic(), settings);
  // A device turned a quarter turn about z relative to the world: its x is the world's y.
  DeviceMapping mapping = rig.coupling->mapping();
  mapping.anchor.rotation = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
  mapping.position_scale = 10;  // 1 cm on the desk is 10 cm in the scene
  rig.coupling = std::make_unique<HandCoupling>(*rig.hand, mapping, settings);
  rig.step(device::Pose{});
  rig.step(displaced(0, 0.01));  // device x = world y, 0.1 m
  EXPECT_NEAR(rig.coupling->worldWrench().force.y(), -1e5 * 0.1 * 0.1, 1e-6);
  EXPECT_NEAR(rig.published.wrench.force.x, -1e5 * 0.1 * 0.1, 1e-6);  // back in device x
  EXPECT_NEAR(rig.published.wrench.force.y, 0, 1e-6);
  // K_d = R^T K R scaled: dF_x/dx_device = -E c_f * 10.
  EXPECT_NEAR(rig.published.stiffness[0], -1e5 * 0.1 * 10, 1e-6);
}

TEST(HapticRuntime, LockstepLoopRendersAForceOpposingThePush) {
  // Device -> loop -> coupling -> world -> coupling -> loop -> device, on a simulated clock.
  // dt = 0.01, CG, as the twist scenes. Strong mass damping keeps this very soft cylinder (first
  // bending period ~36 s) from ringing, so the sign of the reaction is that of statics.
  SolverSettings solver;
  CouplingRig rig(2430, solver, CouplingSettings{}, 50.0);
  const device::Trajectory push({{0, device::Pose{}}, {0.5, displaced(0, 0.05)}}, {{0, 1u}});
  device::ScriptedDevice scripted(push, device::defaultDeviceLimits(), "push");
  device::HapticLoopSettings loop_settings;
  loop_settings.log_capacity = 2000;
  device::HapticLoop loop(scripted, loop_settings);
  HapticRuntime runtime(*rig.world, {{rig.coupling.get(), &loop, 1000}});
  for (int k = 0; k < 100; ++k)
    ASSERT_TRUE(runtime.stepLockstep().ok);
  EXPECT_TRUE(rig.hand->grabbed());
  EXPECT_TRUE(runtime.warnings().empty());
  EXPECT_LT(scripted.lastWritten().force.x, -0.1);  // N: resists the push along x
  EXPECT_EQ(loop.stats().nonfinite, 0u);
  // Ten loop ticks per step, and the wrench rendered is never older than one step.
  EXPECT_EQ(loop.log().size(), 1000u);
  for (const device::LoopLogRow& row : loop.log()) {
    if (row.sim_step > 0) {
      EXPECT_LE(row.wrench_age, 0.01 + 1e-9);
    }
  }
}

TEST(HandCoupling, ALaggingPatchIsFeltAsAVirtualCouplingThatGivesWayToTheInternalForce) {
  // The device turns 1 rad about z in 0.25 s; the hand's speed limit (0.2 of the shear wave
  // speed: about 1.2 rad/s at this patch's reach) holds the patch back, so the device leads it
  // by up to ~0.7 rad, then the patch catches up.
  SolverSettings solver;
  CouplingRig rig(2430, solver, CouplingSettings{}, 5.0);
  const device::Trajectory turn(
      {{0, device::Pose{}}, {0.25, displaced(5, 1.0)}, {1.5, displaced(5, 1.0)}}, {{0, 1u}});
  device::ScriptedDevice scripted(turn, device::defaultDeviceLimits(), "turn");
  device::HapticLoopSettings loop_settings;
  loop_settings.log_capacity = 2000;
  device::HapticLoop loop(scripted, loop_settings);
  HapticRuntime runtime(*rig.world, {{rig.coupling.get(), &loop, 1000}});
  const double k_r = 1e5 * CouplingSettings{}.torque_coefficient;  // E c_t, N m/rad
  double max_lag = 0, previous_lag = 0, previous_torque = 0, peak_coupling = 0, last_before = 0;
  int growing = 0, caught_up_steps = 0;
  for (int k = 0; k < 150; ++k) {
    ASSERT_TRUE(runtime.stepLockstep().ok);
    const Frame& patch = rig.hand->frame();
    const Frame& goal = rig.coupling->goal();
    const double lag = Eigen::AngleAxisd(goal.rotation * patch.rotation.conjugate()).angle();
    const double torque = rig.coupling->lagWrench().torque.z();
    max_lag = std::max(max_lag, lag);
    peak_coupling = std::max(peak_coupling, std::abs(torque));
    if (lag > 1e-9) {
      EXPECT_LT(torque, 0);                // pulls the device back toward the patch (lag about +z)
      if (k < 24 && lag > previous_lag) {  // the device still turning: the lag grows...
        EXPECT_LT(torque, previous_torque);  // ...and so does the coupling's torque
        ++growing;
      }
    } else {
      // Caught up: the coupling is gone and the rendering is the internal force about the
      // device frame's origin, exactly.
      EXPECT_EQ(rig.coupling->lagWrench().torque.norm(), 0);
      const Wrench internal = rig.body->groupWrench(rig.hand->group(), goal.origin);
      EXPECT_EQ((rig.coupling->worldWrench().torque - internal.torque).norm(), 0);
      EXPECT_EQ((rig.coupling->worldWrench().force - internal.force).norm(), 0);
      if (k > 30) ++caught_up_steps;
      if (previous_lag > 1e-9) last_before = std::abs(previous_torque);
    }
    previous_lag = lag;
    previous_torque = torque;
  }
  EXPECT_GT(max_lag, 0.5);
  EXPECT_GT(growing, 15);
  EXPECT_GT(caught_up_steps, 50);
  EXPECT_GT(peak_coupling, 0.5 * k_r * 0.5);
  // The step before the patch arrives the lag is at most one step of the patch's speed: the
  // coupling has shrunk to a few percent of its peak and then goes (no step back to the
  // internal force larger than that).
  EXPECT_LT(last_before, 0.05 * peak_coupling);
  // What the device got never jumped: every tick within the rate limits.
  const device::SafetySettings limits;
  for (size_t t = 1; t < loop.log().size(); ++t) {
    const device::LoopLogRow& a = loop.log()[t - 1];
    const device::LoopLogRow& b = loop.log()[t];
    EXPECT_LE(device::norm(b.output.torque - a.output.torque),
              limits.max_torque_rate * b.period * (1 + 1e-9));
    EXPECT_LE(device::norm(b.output.force - a.output.force),
              limits.max_force_rate * b.period * (1 + 1e-9));
  }
  std::printf(
      "lag coupling: max lag %.3f rad, peak coupling torque %.4g N m (k_r = %.4g N m/rad), "
      "%.4g N m the step before the patch arrived\n",
      max_lag, peak_coupling, k_r, last_before);
}

}  // namespace
}  // namespace torsion::haptics
