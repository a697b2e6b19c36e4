// The whole chain in closed loop on the FEM cylinder: a simulated device held by a simulated
// operator (arm_device.h) -> haptic loop at 1 kHz -> coupling -> the stiff 2430-tet cylinder
// (E = 1e7 Pa) at 100 Hz -> its wrench, reaching the loop `delay` late -> the device. Lockstep,
// deterministic (docs/haptics.md, "Passivity").

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <deque>
#include <string>

#include "arm_device.h"
#include "coupling_rig.h"
#include "stand_in_simulation.h"
#include "torsion/device/haptic_loop.h"

namespace torsion::haptics {
namespace {

struct ClosedLoop {
  double delay = 0.02;  // s from a step's end to its wrench reaching the loop
  bool passivity = true;
  double energy_tolerance = 0;   // J, passivity.energy_tolerance
  bool local_stiffness = false;  // publish K_h
  double twist = 0.05;           // rad the operator means to turn
  double twist_time = 0.05;
  double wrist_damping = 0.1;
  double tilt_damping = -1;  // N m s/rad about x and y (the grip); negative: wrist_damping
  double duration = 2;
};

struct ClosedTrace {
  std::vector<double> time, angle, torque, simulated;
  double max_energy = 0, dissipated = 0;
  std::uint64_t active = 0;
  double swing(double from, double to) const { return device::peakToPeak(time, angle, from, to); }
  // Mean of `v` over [from, to).
  double mean(const std::vector<double>& v, double from, double to) const {
    double sum = 0;
    int n = 0;
    for (size_t k = 0; k < time.size(); ++k) {
      if (time[k] < from || time[k] >= to) continue;
      sum += v[k];
      ++n;
    }
    return n > 0 ? sum / n : 0.0;
  }
};

ClosedTrace runClosedLoop(const ClosedLoop& c) {
  SolverSettings solver;  // dt = 0.01, CG, as the twist scenes
  CouplingSettings coupling;
  coupling.stiffness_refresh_steps = c.local_stiffness ? 10 : 0;
  DeviceMapping mapping;
  mapping.force_scale = 1e-4;  // G J / L = 6e5 N m/rad in the world: 60 N m/rad at the device
  mapping.torque_scale = 1e-4;
  CouplingRig rig(2430, solver, coupling, 0.0, ElementKind::kTet4, 1e7, &mapping);

  simulated::SimulatedArmSettings arm = device::twistingArm(c.twist, c.twist_time, c.wrist_damping);
  arm.max_force = 30;
  arm.wrist_tilt_damping = c.tilt_damping;
  device::ArmDevice device(arm);
  device::HapticLoopSettings settings;
  settings.passivity.enabled = c.passivity;
  settings.passivity.energy_tolerance = c.energy_tolerance;
  settings.log_capacity = static_cast<size_t>(c.duration * 1000) + 20;
  device::HapticLoop loop(device, settings);

  std::deque<std::pair<double, device::SimulationWrench>> in_flight;
  int tick = 0;
  while (rig.world->time() < c.duration - 1e-9) {
    for (int k = 0; k < 10; ++k, ++tick) {  // the loop's ticks over the coming step
      const double now = tick * 1e-3;
      while (!in_flight.empty() && in_flight.front().first <= now + 1e-9) {
        loop.wrenches().write(in_flight.front().second);
        in_flight.pop_front();
      }
      loop.tick(now);
    }
    device::HandCommand command;
    loop.commands().read(command);
    EXPECT_TRUE(rig.coupling->apply(command, rig.world->time()).ok());
    const WorldStepReport r = rig.world->step();
    EXPECT_TRUE(r.ok) << r.message;
    in_flight.emplace_back(
        rig.world->time() + c.delay,
        rig.coupling->publish(static_cast<std::uint64_t>(rig.world->stepCount())));
  }
  if (const char* dump = std::getenv("TORSION_CLOSED_LOOP_DUMP")) {
    std::string error;
    loop.writeLog(std::string(dump) + (c.passivity ? "_pc.csv" : "_free.csv"), &error);
  }
  ClosedTrace trace;
  for (const device::LoopLogRow& r : loop.log()) {
    trace.time.push_back(r.time);
    trace.angle.push_back(device::toRotationVector(r.pose.orientation).z);
    trace.torque.push_back(r.output.torque.z);
    trace.simulated.push_back(r.simulated.torque.z);
  }
  trace.max_energy = loop.stats().max_port_energy;
  trace.dissipated = loop.stats().pc_dissipated;
  trace.active = loop.stats().pc_active;
  return trace;
}

TEST(HapticClosedLoop, DelayedStiffCylinderGeneratesEnergyUncontrolledAndIsDampedByTheController) {
  for (double delay : {0.005, 0.02, 0.05}) {
    SCOPED_TRACE(delay);
    ClosedLoop c;
    c.delay = delay;
    c.passivity = false;
    const ClosedTrace free = runClosedLoop(c);
    c.passivity = true;
    const ClosedTrace controlled = runClosedLoop(c);
    std::printf(
        "FEM delay %.0f ms: uncontrolled max E_obs %.3g J, swing %.3g -> %.3g rad; "
        "controlled max E_obs %.3g J, swing %.3g -> %.3g rad, dissipated %.3g J in %llu "
        "ticks\n",
        1e3 * delay, free.max_energy, free.swing(0.5, 1.0), free.swing(1.5, 2.0),
        controlled.max_energy, controlled.swing(0.5, 1.0), controlled.swing(1.5, 2.0),
        controlled.dissipated, static_cast<unsigned long long>(controlled.active));
    // Uncontrolled the coupling generates joules (the twisted cylinder holds 0.2 mJ at the
    // device at rest); controlled the port stays passive to within a millijoule, 1e-4 of that,
    // and the swing dies down, to under a tenth of the uncontrolled one.
    EXPECT_GT(free.max_energy, 1.0);
    EXPECT_LT(controlled.max_energy, 1e-3);
    EXPECT_LT(controlled.swing(1.5, 2.0), controlled.swing(0.5, 1.0));
    EXPECT_LT(controlled.swing(1.5, 2.0), 0.1 * free.swing(1.5, 2.0));
    EXPECT_GT(controlled.active, 0u);
  }
}

TEST(HapticClosedLoop,
     WithItsLocalStiffnessTheCouplingStillGeneratesEnergyAndTheControllerTakesItBack) {
  // The default coupling publishes K_h: the loop renders W_sim + K_h (pose - pose_sim). Against
  // a spring that bridges any delay (passivity_test.cpp); against the ringing FEM body it does
  // not: the simulated wrench carries the body's own dynamics, which K_h (a step's stiffness)
  // does not predict, and the port still gains energy.
  for (double delay : {0.005, 0.02, 0.05}) {
    SCOPED_TRACE(delay);
    ClosedLoop c;
    c.delay = delay;
    c.local_stiffness = true;
    c.passivity = false;
    const ClosedTrace free = runClosedLoop(c);
    c.passivity = true;
    const ClosedTrace controlled = runClosedLoop(c);
    std::printf(
        "FEM with K_h, delay %.0f ms: uncontrolled max E_obs %.3g J, swing %.3g -> %.3g "
        "rad; controlled max E_obs %.3g J, swing %.3g rad, %llu active ticks\n",
        1e3 * delay, free.max_energy, free.swing(0.5, 1.0), free.swing(1.5, 2.0),
        controlled.max_energy, controlled.swing(1.5, 2.0),
        static_cast<unsigned long long>(controlled.active));
    EXPECT_GT(free.max_energy, 1.0);
    EXPECT_LT(controlled.max_energy, 1e-3);
    EXPECT_LT(controlled.swing(1.5, 2.0), 0.01);
    EXPECT_LT(controlled.swing(1.5, 2.0), 0.25 * free.swing(1.5, 2.0));
  }
}

// Transparency in a slow twist (0.05 rad over 1.5 s, held; wrist 3 N m/rad and 1 N m s/rad
// about z). The implicit step's tilt stiffness at the device is about 2500 N m/rad (K_h's x and
// y rows), 40 times the twist's: sampled at 100 Hz steps and rendered through the 3 N m, 30 N m/s
// device it is an active element unless the hand damps the tilt (Colgate: a sampled stiffness K
// needs a physical damping above K T / 2). With the tilt held loosely (1 N m s/rad) the loop
// whirls at 18 Hz in x and y and the twist it feels is softened; with a firm grip on the tilt
// (10 N m s/rad) the port stays within a few microjoules of passive and the device feels the
// body's static torsional stiffness: the torque written is the simulated one at that angle.
TEST(HapticClosedLoop, WithAFirmGripOnTheTiltASlowTwistFeelsTheBodysStaticStiffness) {
  ClosedLoop c;
  c.delay = 0;
  c.local_stiffness = true;
  c.passivity = false;
  c.twist_time = 1.5;
  c.wrist_damping = 1.0;
  c.duration = 3;
  const ClosedTrace loose = runClosedLoop(c);
  c.tilt_damping = 10;
  const ClosedTrace firm = runClosedLoop(c);
  auto felt = [](const ClosedTrace& t) { return t.mean(t.torque, 2, 3) / t.mean(t.angle, 2, 3); };
  auto simulated = [](const ClosedTrace& t) {
    return t.mean(t.simulated, 2, 3) / t.mean(t.angle, 2, 3);
  };
  std::printf(
      "slow twist, uncontrolled: loose tilt max E_obs %.3g J, felt %.1f N m/rad (simulated "
      "%.1f); firm tilt max E_obs %.3g J, felt %.1f N m/rad (simulated %.1f), torque %.4f N m\n",
      loose.max_energy, -felt(loose), -simulated(loose), firm.max_energy, -felt(firm),
      -simulated(firm), firm.mean(firm.torque, 2, 3));
  // Loose: joules over 3 s while the twisted body holds about 0.14 mJ at the device.
  EXPECT_GT(loose.max_energy, 0.01);
  // Firm: passive up to under 10 % of the energy the body holds at the device.
  EXPECT_LT(firm.max_energy, 1.4e-5);
  // Felt as simulated (2 %), and the body's stiffness: G J / L = 60 N m/rad at the device, times
  // the coarse mesh's own torsional stiffness error (1.15 on 8332 tets, docs/validation.md).
  EXPECT_NEAR(felt(firm), simulated(firm), 0.02 * std::abs(simulated(firm)));
  EXPECT_GT(-felt(firm), 60.0);
  EXPECT_LT(-felt(firm), 60.0 * 1.35);
  EXPECT_LT(-felt(loose), 0.7 * -felt(firm));

  // The controllers against this reference. Strict (the default), the dead-beat damper acts on
  // the sampled rendering's microjoules, chatters and softens the twist (measured: 2.5 % less
  // torque at 1.8 times the angle). With a 10 uJ tolerance it leaves the loop alone: the same
  // torque within 2 %, and the port within the tolerance.
  c.passivity = true;
  const ClosedTrace strict = runClosedLoop(c);
  c.energy_tolerance = 1e-5;
  const ClosedTrace tolerant = runClosedLoop(c);
  const double reference = firm.mean(firm.torque, 2, 3);
  std::printf(
      "controlled: strict %.4f N m at %.5f rad (max E_obs %.3g J, %llu active ticks); 10 uJ "
      "tolerance %.4f N m at %.5f rad (max E_obs %.3g J, %llu active ticks)\n",
      strict.mean(strict.torque, 2, 3), strict.mean(strict.angle, 2, 3), strict.max_energy,
      static_cast<unsigned long long>(strict.active), tolerant.mean(tolerant.torque, 2, 3),
      tolerant.mean(tolerant.angle, 2, 3), tolerant.max_energy,
      static_cast<unsigned long long>(tolerant.active));
  EXPECT_NEAR(tolerant.mean(tolerant.torque, 2, 3), reference, 0.02 * std::abs(reference));
  EXPECT_NEAR(felt(tolerant), felt(firm), 0.02 * std::abs(felt(firm)));
  EXPECT_LE(tolerant.max_energy, 1e-5 * (1 + 1e-9));
}

}  // namespace
}  // namespace torsion::haptics
