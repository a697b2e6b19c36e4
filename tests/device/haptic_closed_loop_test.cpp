// The whole chain in closed loop on the FEM cylinder: a simulated device held by a simulated
// operator (arm_device.h) -> haptic loop at 1 kHz -> coupling -> the stiff 2430-tet cylinder
// (E = 1e7 Pa) at 100 Hz -> its wrench, reaching the loop `delay` late -> the device. Lockstep,
// deterministic (docs/haptics.md, "Passivity").

#include <gtest/gtest.h>

#include <algorithm>
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
  bool rate_limited = device::PassivitySettings{}.rate_limited;  // passivity.rate_limited
  // passivity.misprediction_margin; 0: the plain dead-beat damper
  double margin = device::PassivitySettings{}.misprediction_margin;
  double energy_tolerance = 0;   // J, passivity.energy_tolerance
  bool local_stiffness = false;  // publish K_h
  double twist = 0.05;           // rad the operator means to turn
  double twist_time = 0.05;
  double wrist_damping = 0.1;
  double tilt_damping = -1;  // N m s/rad about x and y (the grip); negative: wrist_damping
  double duration = 2;
  double step_blend_hz = device::HapticLoopSettings{}.step_blend_hz;
  Rendering rendering = Rendering::kInternalForce;
};

struct ClosedTrace {
  std::vector<double> time, angle, torque, simulated, energy;
  double max_energy = 0, dissipated = 0;
  double max_torque_step = 0;  // N m, largest change of the written torque in one tick
  std::uint64_t active = 0;
  double swing(double from, double to) const { return device::peakToPeak(time, angle, from, to); }
  // Largest |angle - other's angle| over [from, to): the oscillation about another run's motion
  // (same ticks).
  double deviation(const ClosedTrace& other, double from, double to) const {
    double worst = 0;
    for (size_t k = 0; k < time.size() && k < other.time.size(); ++k)
      if (time[k] >= from && time[k] < to)
        worst = std::max(worst, std::abs(angle[k] - other.angle[k]));
    return worst;
  }
  // E_obs (J) at the last tick before `t`.
  double energyAt(double t) const {
    double e = 0;
    for (size_t k = 0; k < time.size() && time[k] < t; ++k)
      e = energy[k];
    return e;
  }
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
  coupling.rendering = c.rendering;
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
  settings.passivity.rate_limited = c.rate_limited;
  settings.passivity.misprediction_margin = c.margin;
  settings.step_blend_hz = c.step_blend_hz;
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
    loop.writeLog(std::string(dump) + "_" + std::to_string(static_cast<int>(1e3 * c.delay)) +
                      "ms_blend" + std::to_string(static_cast<int>(c.step_blend_hz)) +
                      (c.passivity ? (c.rate_limited ? "_rl.csv"
                                      : c.margin > 0 ? "_pc.csv"
                                                     : "_plain.csv")
                                   : "_free.csv"),
                  &error);
  }
  ClosedTrace trace;
  const device::LoopLogRow* previous = nullptr;
  for (const device::LoopLogRow& r : loop.log()) {
    if (previous != nullptr)
      trace.max_torque_step =
          std::max(trace.max_torque_step, device::norm(r.output.torque - previous->output.torque));
    previous = &r;
    trace.time.push_back(r.time);
    trace.angle.push_back(device::toRotationVector(r.pose.orientation).z);
    trace.torque.push_back(r.output.torque.z);
    trace.simulated.push_back(r.simulated.torque.z);
    trace.energy.push_back(r.port_energy);
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
    // device at rest); under the default (rate-limited) controller the port stays passive within
    // 1 % of what the body holds (measured 4.7e-8 J, in the grab's first ticks), and the swing
    // dies down, to about a milliradian, under half the uncontrolled one.
    EXPECT_GT(free.max_energy, 1.0);
    EXPECT_LE(controlled.max_energy, 2e-6);
    EXPECT_LT(controlled.swing(1.5, 2.0), controlled.swing(0.5, 1.0));
    EXPECT_LT(controlled.swing(1.5, 2.0), 0.002);
    EXPECT_LT(controlled.swing(1.5, 2.0), 0.5 * free.swing(1.5, 2.0));
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
    EXPECT_LE(controlled.max_energy, 2e-6);  // 1 % of the 0.2 mJ the body holds (as above)
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
  c.step_blend_hz = 0;  // the reference: the rendering as simulated
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

  // The controller against this reference. Strict (the default), it acts on the sampled
  // rendering's microjoules and keeps the port passive within 1 % of the 0.14 mJ the body holds
  // at the device, at a torque within 2 % of the reference.
  // With a 10 uJ tolerance it leaves the loop alone: the same torque and felt stiffness within
  // 2 %, and the port within the tolerance.
  c.passivity = true;
  c.step_blend_hz = ClosedLoop{}.step_blend_hz;  // the default configuration
  const ClosedTrace strict = runClosedLoop(c);
  c.energy_tolerance = 1e-5;
  c.step_blend_hz = 0;
  const ClosedTrace tolerant = runClosedLoop(c);
  const double reference = firm.mean(firm.torque, 2, 3);
  std::printf(
      "controlled: strict %.4f N m at %.5f rad (max E_obs %.3g J, %llu active ticks); 10 uJ "
      "tolerance %.4f N m at %.5f rad (max E_obs %.3g J, %llu active ticks)\n",
      strict.mean(strict.torque, 2, 3), strict.mean(strict.angle, 2, 3), strict.max_energy,
      static_cast<unsigned long long>(strict.active), tolerant.mean(tolerant.torque, 2, 3),
      tolerant.mean(tolerant.angle, 2, 3), tolerant.max_energy,
      static_cast<unsigned long long>(tolerant.active));
  EXPECT_LE(strict.max_energy, 1.4e-6);
  EXPECT_NEAR(strict.mean(strict.torque, 2, 3), reference, 0.02 * std::abs(reference));
  EXPECT_NEAR(tolerant.mean(tolerant.torque, 2, 3), reference, 0.02 * std::abs(reference));
  EXPECT_NEAR(felt(tolerant), felt(firm), 0.02 * std::abs(felt(firm)));
  EXPECT_LE(tolerant.max_energy, 1e-5 * (1 + 1e-9));
}

// The delayed stiff cylinder in the slow twist (as above, firm grip), with the step blend
// (step_blend.h, 8 Hz) under the default controller (rate-limited). Without a controller the
// delayed loop gains energy in the twist and keeps oscillating; with it the port stays passive,
// the motion settles, the torque never steps beyond the rate limit, and the hold's torque is the
// one felt without delay and without any controller: the reference, since that loop is passive
// on its own (the test above) and a delay does not change the static equilibrium of a passive
// body and the operator's wrist. Without the blend the hold is softer (printed here).
TEST(HapticClosedLoop, ADelayedSlowTwistStaysPassiveAndFeelsTheUndelayedTorqueUnderTheController) {
  ClosedLoop c;
  c.delay = 0;
  c.local_stiffness = true;
  c.passivity = false;
  c.twist_time = 1.5;
  c.wrist_damping = 1.0;
  c.tilt_damping = 10;
  c.duration = 3;
  c.step_blend_hz = 0;  // the reference: the rendering as simulated
  const ClosedTrace reference = runClosedLoop(c);
  const double torque = reference.mean(reference.torque, 2, 3);
  const double angle = reference.mean(reference.angle, 2, 3);
  ASSERT_LT(reference.max_energy, 1.4e-5);  // passive: the reference is safe
  const double rate_step = 30 * 1e-3;       // N m per tick: the safety filter's 30 N m/s
  auto off = [&](const ClosedTrace& t) { return 100 * (t.mean(t.torque, 2, 3) / torque - 1); };
  for (double delay : {0.005, 0.02, 0.05}) {
    SCOPED_TRACE(delay);
    c.delay = delay;
    c.step_blend_hz = 0;
    c.passivity = true;
    const ClosedTrace unblended = runClosedLoop(c);
    c.step_blend_hz = ClosedLoop{}.step_blend_hz;  // the default, 8 Hz
    c.passivity = false;
    const ClosedTrace free = runClosedLoop(c);
    c.passivity = true;
    const ClosedTrace controlled = runClosedLoop(c);
    std::printf(
        "slow twist, delay %.0f ms (blend 8 Hz; reference %.4f N m at %.5f rad): uncontrolled "
        "E_obs %.3g J at 1 s, %.3g J at 3 s, off the undelayed twist by %.3g rad in 0.1-0.3 s, "
        "%.3g in 2.5-3 s; default: max E_obs %.3g J, largest step %.3g N m, swing %.3g -> %.3g "
        "rad, torque %.4f N m (%+.2f %%) at %.5f rad, %llu active ticks; default unblended: max "
        "E_obs %.3g J, swing %.3g rad, torque %.4f N m (%+.2f %%) at %.5f rad\n",
        1e3 * delay, torque, angle, free.energyAt(1), free.energyAt(3),
        free.deviation(reference, 0.1, 0.3), free.deviation(reference, 2.5, 3),
        controlled.max_energy, controlled.max_torque_step, controlled.swing(1, 1.5),
        controlled.swing(2.5, 3), controlled.mean(controlled.torque, 2, 3), off(controlled),
        controlled.mean(controlled.angle, 2, 3), static_cast<unsigned long long>(controlled.active),
        unblended.max_energy, unblended.swing(2.5, 3), unblended.mean(unblended.torque, 2, 3),
        off(unblended), unblended.mean(unblended.angle, 2, 3));
    // Uncontrolled: the port gains energy, far beyond the 0.14 mJ the twisted body holds at the
    // device, and keeps gaining it; the oscillation about the undelayed twist grows from the
    // twist's start to the hold.
    EXPECT_GT(free.energyAt(1), 0.01);
    EXPECT_GT(free.energyAt(3), free.energyAt(1));
    EXPECT_GT(free.deviation(reference, 2.5, 3), 2 * free.deviation(reference, 0.1, 0.3));
    // Controlled: E_obs within 1 % of what the body holds, the motion settled to under a
    // milliradian and a tenth of the uncontrolled swing, no step beyond the rate limit, and the
    // torque of the hold within 2 % of the reference. The torque of the hold is mostly the
    // operator's wrist (3 N m/rad against the body's 74), so the angle says more of the
    // stiffness felt: within a fifth of the undelayed angle.
    for (const ClosedTrace* t : {&controlled, &unblended}) {
      EXPECT_LE(t->max_energy, 1.4e-6);
      EXPECT_LE(t->max_torque_step, rate_step * (1 + 1e-9));
    }
    EXPECT_LT(controlled.swing(2.5, 3), 1e-3);
    EXPECT_LT(controlled.swing(2.5, 3), 0.1 * free.swing(2.5, 3));
    EXPECT_NEAR(controlled.mean(controlled.torque, 2, 3), torque, 0.02 * std::abs(torque));
    EXPECT_NEAR(controlled.mean(controlled.angle, 2, 3), angle, 0.2 * angle);
  }
}

// The fast turn (0.05 rad in 0.05 s) asks the torque to rise at 60 N m/s (the body's 74 N m/rad
// at 1 rad/s; the step's own stiffness is 20 times that) where the rate limit allows 30. Within
// the rate limit the torque cannot keep up while the hand presses in, the port stores less than
// the body holds, and a strictly passive port may not give the difference back: the hand sinks
// in (a passive rendering that never steps beyond the rate limit r cannot feel stiffer than
// r / v at speed v). Both controllers stay within the rate limit; the default, rate-limited one
// plans for it and stays passive, with and without K_h; the dead-beat damper, its correction
// spread by the rate limit, lets energy through.
TEST(HapticClosedLoop, AFastTurnStaysPassiveWithinTheRateLimit) {
  const double rate_step = 30 * 1e-3;
  for (double delay : {0.005, 0.02, 0.05}) {
    SCOPED_TRACE(delay);
    ClosedLoop c;
    c.delay = delay;
    const ClosedTrace limited = runClosedLoop(c);
    c.local_stiffness = true;
    const ClosedTrace stiff = runClosedLoop(c);
    c.local_stiffness = false;
    c.rate_limited = false;
    const ClosedTrace dead_beat = runClosedLoop(c);
    auto hold = [](const ClosedTrace& t) { return t.mean(t.angle, 1.5, 2); };
    std::printf(
        "fast turn, delay %.0f ms: default (rate-limited) holds %.4f rad with %.4f N m against "
        "%.4f simulated (largest step %.3g N m, max E_obs %.3g J), with K_h %.4f rad (step %.3g "
        "N m, max E_obs %.3g J); dead-beat %.4f rad (step %.3g N m, max E_obs %.3g J)\n",
        1e3 * delay, hold(limited), limited.mean(limited.torque, 1.5, 2),
        limited.mean(limited.simulated, 1.5, 2), limited.max_torque_step, limited.max_energy,
        hold(stiff), stiff.max_torque_step, stiff.max_energy, hold(dead_beat),
        dead_beat.max_torque_step, dead_beat.max_energy);
    for (const ClosedTrace* t : {&limited, &stiff, &dead_beat})
      EXPECT_LE(t->max_torque_step, rate_step * (1 + 1e-9));
    // Passive within 1 % of the 0.2 mJ the body holds at the device.
    EXPECT_LE(limited.max_energy, 2e-6);
    EXPECT_LE(stiff.max_energy, 2e-6);
    // The hand is held short of the 0.05 rad it meant to turn, the torque against it.
    EXPECT_LT(hold(limited), 0.05);
    EXPECT_LT(limited.mean(limited.torque, 1.5, 2), 0);
  }
}

// The report's frame-difference rendering through the same loop, under the default controller
// and under the rate-limited one: a spring of E c_t = 1e7 * 0.05 m^3, 50 N m/rad at the device,
// to the grab pose. The slow twist (firm grip, no delay) is felt as that spring.
TEST(HapticClosedLoop, TheFrameDifferenceRenderingIsFeltAsItsSpringUnderEitherController) {
  // Its K_h = diag(-E c_f, -E c_t) is exact, so the local model is the spring of the current
  // pose and bridges the delay: passive, and felt as the spring, at 0 and at 50 ms.
  ClosedLoop c;
  c.local_stiffness = true;
  c.rendering = Rendering::kFrameDifference;
  c.twist_time = 1.5;
  c.wrist_damping = 1.0;
  c.tilt_damping = 10;
  c.duration = 3;
  const double spring = 1e7 * CouplingSettings{}.torque_coefficient * 1e-4;  // N m/rad
  for (double delay : {0.0, 0.05}) {
    for (bool rate_limited : {false, true}) {
      SCOPED_TRACE(delay);
      SCOPED_TRACE(rate_limited);
      c.delay = delay;
      c.rate_limited = rate_limited;
      const ClosedTrace t = runClosedLoop(c);
      const double felt = -t.mean(t.torque, 2, 3) / t.mean(t.angle, 2, 3);
      std::printf(
          "frame difference, delay %.0f ms, %s: felt %.2f N m/rad (spring %.1f), max E_obs %.3g "
          "J, %llu active ticks, largest step %.3g N m\n",
          1e3 * delay, rate_limited ? "rate-limited" : "dead-beat", felt, spring, t.max_energy,
          static_cast<unsigned long long>(t.active), t.max_torque_step);
      EXPECT_NEAR(felt, spring, 0.02 * spring);
      EXPECT_LE(t.max_energy, 1e-6);
      EXPECT_LT(t.swing(2.5, 3), 1e-3);
    }
  }
}

}  // namespace
}  // namespace torsion::haptics
