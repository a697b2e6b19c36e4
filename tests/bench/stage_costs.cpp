// stage_costs: the time of each stage of an implicit step, each measured alone and repeated, on
// a twisted cylinder (the twist protocol's first ramp steps), with the sizes that set each
// stage's minimum work (blocks of K, entries of the Cholesky factor). One JSON line. The
// roofline of docs/performance.md puts these against machine_probe's ceilings.
//
//   stage_costs --mesh cylinder_8332 [--element tet10] [--threads 1] [--E 1e5] [--reps 50]

#include <time.h>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/LU>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "torsion/fem/corotated_element.h"
#include "torsion/fem/factored_tet_hessian.h"
#include "torsion/fem/fem_model.h"
#include "torsion/mesh/mesh_io.h"
#include "torsion/solve/cholmod_solver.h"
#include "torsion/solve/implicit_stepper.h"
#include "twist_protocol.h"

namespace {

double processCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

// The mean process CPU time of `reps` calls, ms, the least of three rounds: CPU time, not wall
// time, because the machine is shared (bench_twist's cpu_ms_per_step is the same measure).
template <class Fn>
double timeMs(int reps, Fn&& fn) {
  double best = 1e300;
  for (int round = 0; round < 3; ++round) {
    const double t0 = processCpuMs();
    for (int r = 0; r < reps; ++r)
      fn();
    best = std::min(best, (processCpuMs() - t0) / reps);
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace torsion;
  std::string mesh_name = "cylinder_8332", element = "tet4";
  int threads = 1, reps = 50;
  double youngs = 1e5;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--mesh")) mesh_name = argv[i + 1];
    if (!std::strcmp(argv[i], "--element")) element = argv[i + 1];
    if (!std::strcmp(argv[i], "--threads")) threads = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--reps")) reps = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--E")) youngs = std::atof(argv[i + 1]);
  }
  std::string path = mesh_name;
  if (path.find('/') == std::string::npos) path = std::string(TORSION_ASSETS_DIR) + "/" + path;
  auto loaded = readMesh(path);
  if (!loaded.ok()) {
    std::fprintf(stderr, "stage_costs: %s\n", loaded.error().message.c_str());
    return 2;
  }
  auto mesh = std::make_shared<const TetMesh>(std::move(loaded.value().mesh));
  Material material;
  material.youngs_modulus = youngs;
  material.stiffness_damping = 0.01;
  auto model = FemModel::create(mesh, material,
                                element == "tet10" ? ElementKind::kTet10 : ElementKind::kTet4)
                   .value();
  const Parallel parallel(threads);
  SolverSettings settings;
  ImplicitStepper stepper(model, settings, parallel);
  FemState state = FemState::atRest(*model);
  // Twist the far end by 0.3 rad over 30 steps: rotations far from identity.
  const bench::TwistScene scene = bench::classifyNodes(model->mesh());
  NodeConstraints constraints(model->nodeCount());
  const Eigen::VectorXd no_force = Eigen::VectorXd::Zero(3 * model->nodeCount());
  const double dt = settings.time_step;
  for (int k = 0; k < 30; ++k) {
    for (int i = 0; i < model->nodeCount(); ++i) {
      const bench::NodeRole role = scene.roles[static_cast<size_t>(i)];
      if (role == bench::NodeRole::kFixed)
        constraints.prescribeVelocity(i, Eigen::Vector3d::Zero());
      if (role == bench::NodeRole::kDriven) {
        const Eigen::Vector3d target = bench::turnedAboutZ(
            model->mesh().restPositions()[static_cast<size_t>(i)], 0.01 * (k + 1));
        constraints.prescribeVelocity(i, (target - state.position(i)) / dt);
      }
    }
    stepper.step(state, constraints, no_force);
  }

  SystemOperator op(model, parallel);
  op.mutableRotations() = stepper.system().rotations();
  op.setCoefficients(1.0, dt * dt + dt * material.stiffness_damping);
  const double rotations_forces_ms = timeMs(reps, [&] {
    FemState copy = state;
    stepper.computeElasticForces(copy);
  });
  const double copy_ms = timeMs(reps, [&] { FemState copy = state; });
  const double assembly_ms = timeMs(reps, [&] {
    op.mutableRotations();  // marks K stale
    op.stiffnessBlocks();
  });
  // The stable neo-Hookean tet4's exact Hessian from its factors (fem/factored_tet_hessian.h), at
  // the same positions: the assembly a Newton direction pays instead of the corotated one.
  double factored_assembly_ms = 0;
  if (model->elementKind() == ElementKind::kTet4) {
    ElementStiffnesses factored;
    factored.factored_shear = material.mu();
    const std::vector<int>& nodes = model->elementNodes();
    for (size_t e = 0; e < static_cast<size_t>(model->elementCount()); ++e) {
      std::array<Eigen::Vector3d, 4> x;
      for (size_t a = 0; a < 4; ++a)
        x[a] = state.position(nodes[4 * e + a]);
      const TetRestData& rest = model->tetRestData()[e];
      const Eigen::Matrix3d F = deformationGradient(x, rest.rest_shape_inverse);
      factored.factored_tet4.push_back(
          factoredTetHessian(F, shapeGradients(rest.rest_shape_inverse), rest.volume,
                             material.lambda(), material.lambda() * (F.determinant() - 1)));
    }
    SystemOperator hessian(model, parallel);
    hessian.setElementStiffnesses(&factored);
    factored_assembly_ms = timeMs(reps, [&] {
      hessian.setElementStiffnesses(&factored);  // marks K stale
      hessian.stiffnessBlocks();
    });
  }
  Eigen::VectorXd y = state.velocities, out;
  y.array() += 0.1;
  const double product_ms = timeMs(reps, [&] { op.multiply(y, out); });
  std::vector<Eigen::Matrix3d> blocks;
  const double block_jacobi_setup_ms = timeMs(reps, [&] {
    op.diagonalBlocks(blocks);
    for (Eigen::Matrix3d& b : blocks)
      b = b.inverse().eval();
  });
  const double block_jacobi_apply_ms = timeMs(reps, [&] {
    for (size_t i = 0; i < blocks.size(); ++i)
      out.segment<3>(3 * static_cast<Eigen::Index>(i)) =
          blocks[i] * y.segment<3>(3 * static_cast<Eigen::Index>(i));
  });
  CholmodSolver assembler;
  const Eigen::SparseMatrix<double>& A = assembler.assemble(op, constraints);
  const double cholmod_assembly_ms = timeMs(5, [&] { assembler.assemble(op, constraints); });
  SparseCholesky cholesky;
  cholesky.factorize(A);
  const double factor_ms = timeMs(3, [&] { cholesky.factorize(A); });
  const double solve_ms = timeMs(reps, [&] { cholesky.solve(y, out); });
  Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>> incomplete;
  const double ic_factor_ms = timeMs(3, [&] { incomplete.compute(A); });
  const double ic_solve_ms = timeMs(reps, [&] { out = incomplete.solve(y); });
  const long ic_entries = static_cast<long>(incomplete.matrixL().nonZeros());
  // Eigen's simplicial LDL^T (AMD order): no supernodes, no BLAS; its solve is two plain sweeps.
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt;
  ldlt.analyzePattern(A);
  const double ldlt_factor_ms = timeMs(3, [&] { ldlt.factorize(A); });
  const double ldlt_solve_ms = timeMs(reps, [&] { out = ldlt.solve(y); });
  const long ldlt_entries = static_cast<long>(ldlt.matrixL().nestedExpression().nonZeros());

  std::printf(
      "{\"mesh\": \"%s\", \"element\": \"%s\", \"nodes\": %d, \"elements\": %d, \"threads\": %d, "
      "\"E\": %g, \"k_blocks_upper\": %zu, \"A_lower_entries\": %ld, \"cholesky_factor_entries\": "
      "%ld, \"ic_factor_entries\": %ld, \"ms_rotations_forces\": %.4f, \"ms_assembly\": %.4f, "
      "\"ms_factored_assembly\": %.4f, "
      "\"ms_product\": %.4f, \"ms_block_jacobi_setup\": %.4f, \"ms_block_jacobi_apply\": %.4f, "
      "\"ms_cholmod_matrix\": %.4f, \"ms_cholmod_factor\": %.4f, \"ms_cholmod_solve\": %.4f, "
      "\"ms_ic_factor\": %.4f, \"ms_ic_solve\": %.4f, \"ldlt_factor_entries\": %ld, "
      "\"ms_ldlt_factor\": %.4f, \"ms_ldlt_solve\": %.4f}\n",
      mesh_name.c_str(), element.c_str(), model->nodeCount(), model->elementCount(), threads,
      youngs, op.blockColumns().size(), static_cast<long>(A.nonZeros()), cholesky.factorEntries(),
      ic_entries, rotations_forces_ms - copy_ms, assembly_ms, factored_assembly_ms, product_ms,
      block_jacobi_setup_ms, block_jacobi_apply_ms, cholmod_assembly_ms, factor_ms, solve_ms,
      ic_factor_ms, ic_solve_ms, ldlt_entries, ldlt_factor_ms, ldlt_solve_ms);
  return 0;
}
