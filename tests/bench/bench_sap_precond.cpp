// The SAP contact solve's cost against the same body's plain step (docs/contact-sap.md, "Cost").
// A 0.4 x 0.4 x 0.1 m slab (16 x 16 x 4 cells, 1445 nodes), E = 1e5 or 1e8 Pa, one step of 1 ms
// from rest under gravity: a rigid 2 kg box resting on four top nodes ("box", 4 rows), or that
// box and every bottom node on the ground ("ground", 293 rows). Times per solve:
//   plain_cg       A v = b by the body's CG (block-Jacobi, tolerance 1e-4), no contact
//   plain_cholmod  A v = b by CHOLMOD (assemble, factorise, solve), no contact
//   sap_*          the island's SAP solve (tolerance 1e-6) with the CG preconditioned by
//     coupled         block-Jacobi on A with the contact terms whole (coupled_preconditioner.h)
//     coupled_1e-4    the same at the tolerance of the body's CG, 1e-4: how the island step
//                     solves an island of CG bodies (island_step.cpp), equal accuracy with
//                     plain_cg
//     factor          the step's CHOLMOD factor for the slab (factorisation included) with the
//                     capacitance correction (sap_solver.h), which above max_correction_rows = 32
//                     rows gives way to coupled (the factorisation still paid)
//     factor_all      the same with the correction at any number of rows
// Counters: Newton and CG iterations per solve (plain: CG iterations), rows, nodes, tets.
// Run: build/tests/bench/bench_sap_precond --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <string>

#include "../contact/solve/sap_fem_scene.h"
#include "torsion/contact/solve/sap_solver.h"
#include "torsion/solve/cholmod_solver.h"
#include "torsion/solve/projected_cg.h"

namespace {

using torsion::sap::test::SlabScene;
using torsion::sap::test::SlabSpec;

enum Method {
  kPlainCg,
  kPlainCholmod,
  kSapCoupled,
  kSapCoupledBodyTolerance,
  kSapFactor,
  kSapFactorAll
};

SlabSpec slabSpec(int log10_e, bool ground, int dt_ms) {
  SlabSpec spec;
  spec.dt = 1e-3 * dt_ms;
  spec.size = Eigen::Vector3d(0.4, 0.4, 0.1);
  spec.nx = 16;
  spec.ny = 16;
  spec.nz = 4;
  spec.youngs_modulus = log10_e == 8 ? 1e8 : 1e5;
  spec.ground = ground;
  return spec;
}

void plainStep(benchmark::State& state, SlabScene& scene, Method method) {
  torsion::SolverSettings settings;
  settings.time_step = scene.dt();
  settings.max_iterations = 100000;
  torsion::ProjectedCg cg;
  torsion::CholmodSolver cholmod;
  Eigen::VectorXd v;
  torsion::LinearSolveReport report;
  for (auto _ : state) {
    v.setZero(3 * scene.nodeCount());
    report = method == kPlainCg
                 ? cg.solve(scene.system(), scene.constraints(), scene.momentum(), settings, v)
                 : cholmod.solve(scene.system(), scene.constraints(), scene.momentum(), v);
    benchmark::DoNotOptimize(v.data());
  }
  if (!report.converged) state.SkipWithError("plain solve did not converge");
  state.counters["cg"] = report.iterations;
  state.counters["newton"] = 0;
}

void sapStep(benchmark::State& state, SlabScene& scene, Method method) {
  torsion::sap::SapSolverSettings settings;
  settings.max_cg_iterations = 100000;
  if (method == kSapFactorAll) settings.max_correction_rows = 1 << 30;
  if (method == kSapCoupledBodyTolerance) settings.relative_tolerance = 1e-4;
  torsion::sap::SapSolver solver(settings);
  torsion::CholmodSolver factor;
  const torsion::sap::RigidBody box = scene.boxBody();
  Eigen::VectorXd v;
  torsion::sap::SapReport report;
  const std::vector<Eigen::Vector3d>& points = scene.system().model().mesh().restPositions();
  Eigen::VectorXd rest(3 * static_cast<Eigen::Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i)
    rest.segment<3>(3 * static_cast<Eigen::Index>(i)) = points[i];
  for (auto _ : state) {
    torsion::sap::FemIslandBody slab(scene.system(), scene.constraints(), scene.momentum());
    if (method == kSapFactor || method == kSapFactorAll) {
      if (!factor.factorize(scene.system(), scene.constraints())) {
        state.SkipWithError("factorisation failed");
        return;
      }
      slab.usePreconditioner(factor);
    } else {
      slab.useCoarseSpace(rest);  // as the island step does: the slab at rest
    }
    const torsion::sap::SapProblem problem = scene.problem(slab, box);
    v.resize(0);
    report = solver.solve(problem, v);
    benchmark::DoNotOptimize(v.data());
  }
  if (!report.converged) state.SkipWithError(("SAP: " + report.message).c_str());
  state.counters["newton"] = report.newton_iterations;
  state.counters["cg"] = report.cg_iterations;
}

void BM_SlabStep(benchmark::State& state) {
  const auto log10_e = static_cast<int>(state.range(0));
  const bool ground = state.range(1) != 0;
  const auto method = static_cast<Method>(state.range(2));
  const auto dt_ms = static_cast<int>(state.range(3));
  SlabScene scene(slabSpec(log10_e, ground, dt_ms));
  if (method == kPlainCg || method == kPlainCholmod) {
    plainStep(state, scene, method);
  } else {
    sapStep(state, scene, method);
  }
  state.counters["rows"] = static_cast<double>(scene.rows().size());
  state.counters["nodes"] = scene.nodeCount();
  state.counters["tets"] = scene.tetCount();
  static const char* const kNames[] = {"plain_cg",         "plain_cholmod", "sap_coupled",
                                       "sap_coupled_1e-4", "sap_factor",    "sap_factor_all"};
  state.SetLabel(std::string(kNames[method]) + (ground ? " ground" : " box") + " E=1e" +
                 std::to_string(log10_e) + " dt=" + std::to_string(dt_ms) + "ms");
}

void slabArguments(benchmark::internal::Benchmark* b) {
  for (int dt_ms : {1, 10})
    for (int log10_e : {5, 8})
      for (int ground : {0, 1})
        for (int method = kPlainCg; method <= kSapFactorAll; ++method)
          b->Args({log10_e, ground, method, dt_ms});
}

BENCHMARK(BM_SlabStep)
    ->Apply(slabArguments)
    ->ArgNames({"logE", "ground", "method", "dt_ms"})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
