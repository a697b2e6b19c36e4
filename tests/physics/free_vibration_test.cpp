// Free vibration without damping, as backward Euler predicts it (docs/validation.md, "Free
// vibration"). The cantilever of clamped_beam.h (10 x 1 x 1 m, E = 1 GPa, 20 x 2 x 2 cells) is
// bent by a small load (1 m/s^2: Euler-Bernoulli's tip 1.5 cm, strains below 1e-3), released at
// rest, and stepped with no damping at dt = 5 ms (about 100 to 125 steps a period), for every
// material law on tet4 and tet10.
//
// Backward Euler applied to one undamped mode of angular frequency w, v' = v - h w^2 x',
// x' = x + h v', has the step matrix with eigenvalues 1 / (1 -+ i w h): each step turns the mode
// by atan(w h) and scales it by 1 / sqrt(1 + (w h)^2). So
//   - the period seen is T_h = 2 pi h / atan(w h), and
//   - the mode's energy falls by 1 / (1 + (w h)^2) per step, exactly, for a linear system.
// The static deflection under a uniform load is, to a fraction of a percent of its energy, the
// first mode, and its Rayleigh quotient w_R^2 = u^T K u / u^T M u (u^T K u = 2 x the elastic
// energy stored, u^T M u = sum of m_i |u_i|^2) gives that mode's frequency to a fraction of a
// percent too (the quotient is stationary at an eigenvector). Checked:
//   - the total energy never rises from one step to the next (backward Euler dissipates: with a
//     convex potential, E(x_n) >= E(x_n+1) + grad E(x_n+1) . (x_n - x_n+1));
//   - the frequency read from the tip's period, w = tan(2 pi h / T_h) / h, is w_R within 1 %;
//   - the energy after a period and a quarter is E_0 (1 + (w_R h)^2)^-n within 3 % (what is left
//     of the higher modes, which backward Euler damps faster, and the strain's nonlinearity);
//   - the three laws agree with each other (they share the small-strain limit);
//   - on tet10, w_R is Euler-Bernoulli's first frequency 1.875^2 sqrt(E I / (rho A L^4)) within
//     2 % (the coarse linear tets lock and vibrate 28 % faster: printed, not checked).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "clamped_beam.h"

namespace torsion {
namespace {

constexpr double kStep = 5e-3;  // s
constexpr double kPi = 3.14159265358979323846;

struct Vibration {
  double rayleigh_frequency = 0;  // rad/s, of the static shape
  double measured_frequency = 0;  // rad/s, from the tip's period through atan
  double energy_ratio = 0;        // E_n / E_0 after the measured periods
  double predicted_ratio = 0;     // (1 + (w_R h)^2)^-n
  double largest_rise = 0;        // max (E_n+1 - E_n) / E_0
  int steps = 0;
};

double kineticEnergy(const FemModel& model, const FemState& state) {
  double sum = 0;
  for (int i = 0; i < model.nodeCount(); ++i)
    sum += 0.5 * model.nodeMasses()[static_cast<size_t>(i)] * state.velocity(i).squaredNorm();
  return sum;
}

Vibration vibrate(MaterialLaw law, ElementKind element) {
  test::BeamSpec spec;
  spec.cells_across = 2;
  spec.element = element;
  spec.gravity = 1.0;
  spec.material.law = law;
  spec.material.stiffness_damping = 0;
  spec.material.mass_damping = 0;
  test::ClampedBeam beam(spec);
  const StepReport statics = beam.solveStatics();
  EXPECT_FALSE(isFatal(statics.health)) << statics.message;
  const FemModel& model = beam.model();
  // The energies of a state, from a stepper of their own (the beam's keeps its warm starts).
  Parallel parallel(1);
  ImplicitStepper probe(beam.sharedModel(), spec.solver, parallel);
  const auto energy = [&](const FemState& state) {
    FemState copy = state;
    return probe.computeElasticForces(copy) + kineticEnergy(model, state);
  };
  Vibration out;
  // Rayleigh's quotient of the static shape u.
  const double elastic = energy(beam.state());
  double u_m_u = 0;
  const std::vector<Eigen::Vector3d>& rest = model.mesh().restPositions();
  for (int i = 0; i < model.nodeCount(); ++i)
    u_m_u += model.nodeMasses()[static_cast<size_t>(i)] *
             (beam.state().position(i) - rest[static_cast<size_t>(i)]).squaredNorm();
  out.rayleigh_frequency = std::sqrt(2 * elastic / u_m_u);
  // Released: dynamics at kStep, the linear solves exact (CHOLMOD), Newton at its default
  // tolerance (1e-6 of the step's momentum balance).
  SolverSettings dynamic = spec.solver;
  dynamic.time_step = kStep;
  beam.stepper().setSettings(dynamic);
  beam.state().velocities.setZero();
  const double e0 = energy(beam.state());
  double previous_energy = e0, previous_tip = beam.tipDisplacement().z();
  std::vector<double> crossings;  // s, interpolated: the tip through its rest height
  for (int n = 1; crossings.size() < 3 && n < 1000; ++n) {
    const StepReport r = beam.stepUnloaded();
    EXPECT_FALSE(isFatal(r.health))
        << "step " << n << ": " << toString(r.health) << " " << r.message;
    const double e = energy(beam.state());
    out.largest_rise = std::max(out.largest_rise, (e - previous_energy) / e0);
    previous_energy = e;
    const double tip = beam.tipDisplacement().z();
    if ((previous_tip < 0) != (tip < 0))
      crossings.push_back(kStep * (n - 1 + previous_tip / (previous_tip - tip)));
    previous_tip = tip;
    out.steps = n;
  }
  EXPECT_EQ(crossings.size(), 3u);
  if (crossings.size() < 3) return out;
  const double period = crossings[2] - crossings[0];
  out.measured_frequency = std::tan(2 * kPi * kStep / period) / kStep;
  out.energy_ratio = previous_energy / e0;
  out.predicted_ratio = std::pow(1 + std::pow(out.rayleigh_frequency * kStep, 2), -out.steps);
  return out;
}

TEST(FreeVibration, EnergyAndPeriodFollowBackwardEulerForEveryLawAndElement) {
  test::BeamSpec spec;
  const double inertia = std::pow(spec.side, 4) / 12;
  const double euler_bernoulli =
      1.875104 * 1.875104 *
      std::sqrt(spec.material.youngs_modulus * inertia /
                (spec.material.density * spec.side * spec.side * std::pow(spec.length, 4)));
  for (ElementKind element : {ElementKind::kTet4, ElementKind::kTet10}) {
    double corotated_frequency = 0;
    for (MaterialLaw law :
         {MaterialLaw::kCorotated, MaterialLaw::kStableNeoHookean, MaterialLaw::kMooneyRivlin}) {
      const Vibration v = vibrate(law, element);
      std::printf(
          "%s %s: w_R %.6f rad/s (Euler-Bernoulli %.4f), from the period %.6f; energy "
          "after %d steps %.6f of E_0, backward Euler predicts %.6f; largest rise %.2g "
          "E_0\n",
          toString(element), toString(law), v.rayleigh_frequency, euler_bernoulli,
          v.measured_frequency, v.steps, v.energy_ratio, v.predicted_ratio, v.largest_rise);
      const std::string what = std::string(toString(element)) + " " + toString(law);
      EXPECT_LE(v.largest_rise, 1e-9) << what;
      EXPECT_NEAR(v.measured_frequency, v.rayleigh_frequency, 0.01 * v.rayleigh_frequency) << what;
      EXPECT_NEAR(v.energy_ratio, v.predicted_ratio, 0.03 * v.predicted_ratio) << what;
      // The energy really fell (the checks above are not met by a beam that does not move).
      EXPECT_LT(v.energy_ratio, 0.8) << what;
      // Quadratic tets do not lock: the first mode within 2 % of Euler-Bernoulli's (measured
      // +0.3 %: the mesh's stiffness above the shear's -0.6 %).
      if (element == ElementKind::kTet10) {
        EXPECT_NEAR(v.rayleigh_frequency, euler_bernoulli, 0.02 * euler_bernoulli) << what;
      }
      if (law == MaterialLaw::kCorotated) corotated_frequency = v.rayleigh_frequency;
      EXPECT_NEAR(v.rayleigh_frequency, corotated_frequency, 1e-3 * corotated_frequency) << what;
    }
  }
}

}  // namespace
}  // namespace torsion
