// A cantilever slab (one end held, gravity) stepped 30 times by the direct solver and by CG
// solved to 1e-10: both solve the same linear system each step, so the nodes must agree to far
// below the sag (about 1 cm). Prints the factorisation the package was built with.
#include <algorithm>
#include <cstdio>

#include "torsion/bullet/fem_world.h"
#include "torsion/mesh/box_mesh.h"
#include "torsion/solve/cholmod_solver.h"

static torsion::Result<Eigen::VectorXd> run(torsion::LinearSolverKind solver) {
  torsion::WorldSettings settings;
  settings.solver.linear_solver = solver;
  settings.solver.tolerance = 1e-10;
  settings.solver.max_iterations = 5000;
  settings.solver.threads = 1;
  torsion::FemWorld world(settings);
  torsion::Result<torsion::TetMesh> mesh =
      torsion::makeBoxTetMesh({0, 0, 0}, {1, 0.2, 0.1}, 10, 2, 1);
  if (!mesh) return mesh.error();
  torsion::Material material;
  material.youngs_modulus = 1e6;
  torsion::Result<torsion::FemBody*> body = world.addBody("slab", mesh.value(), material);
  if (!body) return body.error();
  std::vector<int> held;
  for (int i = 0; i < body.value()->model().nodeCount(); ++i)
    if (body.value()->state().position(i).x() < 1e-9) held.push_back(i);
  body.value()->carryNodes(
      "held", held, [](double) { return torsion::Frame{}; }, world.time());
  for (int k = 0; k < 30; ++k) {
    const torsion::WorldStepReport report = world.step();
    if (!report.ok) return torsion::Error{report.message};
  }
  const int n = body.value()->model().nodeCount();
  Eigen::VectorXd positions(3 * n);
  for (int i = 0; i < n; ++i)
    positions.segment<3>(3 * i) = body.value()->state().position(i);
  return positions;
}

int main() {
  const torsion::Result<Eigen::VectorXd> direct = run(torsion::LinearSolverKind::kCholmod);
  const torsion::Result<Eigen::VectorXd> cg = run(torsion::LinearSolverKind::kConjugateGradient);
  if (!direct || !cg)
    return std::printf("step failed: %s\n", (!direct ? direct : cg).error().message.c_str()), 1;
  const double difference = (direct.value() - cg.value()).cwiseAbs().maxCoeff();
  double sag = 0;  // lowest z; the slab starts at z >= 0
  for (int i = 2; i < direct.value().size(); i += 3)
    sag = std::min(sag, direct.value()[i]);
  std::printf("direct solver (%s): sag %.4g m, largest difference from CG %.3g m\n",
              torsion::CholmodSolver::backend(), -sag, difference);
  return difference < 1e-6 && sag < -1e-3 ? 0 : 1;
}
