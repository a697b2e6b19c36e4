// The implicit step on small box meshes: invariants that hold exactly (rest, free fall, momentum,
// constraint projection, determinism) or by construction (energy never rises with damping).
#include "torsion/solve/implicit_stepper.h"

#include <gtest/gtest.h>

#include <random>

#include "torsion/fem/corotated_element.h"
#include "torsion/mesh/box_mesh.h"
#include "torsion/solve/cholmod_solver.h"

namespace torsion {
namespace {

std::shared_ptr<const FemModel> beamModel(Material material = {}) {
  auto mesh = std::make_shared<TetMesh>(
      makeBoxTetMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(4, 1, 1), 8, 2, 2).value());
  return FemModel::create(mesh, material).value();
}

Eigen::VectorXd gravityForces(const FemModel& model, const Eigen::Vector3d& g) {
  Eigen::VectorXd f(3 * model.nodeCount());
  for (int i = 0; i < model.nodeCount(); ++i)
    f.segment<3>(3 * i) = model.nodeMasses()[static_cast<size_t>(i)] * g;
  return f;
}

SolverSettings tight(LinearSolverKind kind = LinearSolverKind::kConjugateGradient) {
  SolverSettings s;
  s.linear_solver = kind;
  s.tolerance = 1e-10;
  s.max_iterations = 2000;
  return s;
}

TEST(ImplicitStepper, BodyAtRestStaysAtRest) {
  auto model = beamModel();
  Parallel parallel(1);
  ImplicitStepper stepper(model, tight(), parallel);
  FemState state = FemState::atRest(*model);
  NodeConstraints constraints(model->nodeCount());
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(3 * model->nodeCount());
  for (int k = 0; k < 10; ++k) {
    const StepReport r = stepper.step(state, constraints, zero);
    ASSERT_EQ(r.health, StepHealth::kOk) << r.message;
  }
  EXPECT_LT(state.velocities.cwiseAbs().maxCoeff(), 1e-12);
}

TEST(ImplicitStepper, FreeFallIsExactBackwardEuler) {
  auto model = beamModel();
  Parallel parallel(1);
  const SolverSettings settings = tight();
  ImplicitStepper stepper(model, settings, parallel);
  FemState state = FemState::atRest(*model);
  const FemState start = state;
  NodeConstraints constraints(model->nodeCount());
  const Eigen::Vector3d g(0, 0, -9.81);
  const Eigen::VectorXd f = gravityForces(*model, g);
  const int steps = 20;
  for (int k = 0; k < steps; ++k)
    ASSERT_FALSE(isFatal(stepper.step(state, constraints, f).health));
  const double dt = settings.time_step;
  for (int i = 0; i < model->nodeCount(); ++i) {
    // CG stops at a relative residual of 1e-10 of |M v + dt f| per step: ~1e-9 of v after 20.
    EXPECT_LT((state.velocity(i) - steps * dt * g).norm(), 1e-8);
    const Eigen::Vector3d expected = start.position(i) + dt * dt * steps * (steps + 1) / 2.0 * g;
    EXPECT_LT((state.position(i) - expected).norm(), 1e-8);
  }
}

TEST(ImplicitStepper, InternalForcesConserveMomentum) {
  Material material;
  material.mass_damping = 0;  // drag is the only force that would change momentum
  auto model = beamModel(material);
  Parallel parallel(1);
  ImplicitStepper stepper(model, tight(), parallel);
  FemState state = FemState::atRest(*model);
  std::mt19937 rng(2);
  std::normal_distribution<double> n(0, 0.5);
  for (int i = 0; i < state.velocities.size(); ++i)
    state.velocities[i] = n(rng);
  auto momentum = [&] {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int i = 0; i < model->nodeCount(); ++i)
      p += model->nodeMasses()[static_cast<size_t>(i)] * state.velocity(i);
    return p;
  };
  const Eigen::Vector3d p0 = momentum();
  NodeConstraints constraints(model->nodeCount());
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(3 * model->nodeCount());
  for (int k = 0; k < 30; ++k)
    ASSERT_FALSE(isFatal(stepper.step(state, constraints, zero).health));
  EXPECT_LT((momentum() - p0).norm(), 1e-6 * (p0.norm() + model->totalMass() * 0.5));
}

TEST(ImplicitStepper, InternalForcesAtNodesAreTheWholeVectorsRowsBitForBit) {
  // A node group's wrench reads internalForcesAt(): only its rows of K v, the same bits.
  auto model = beamModel();
  Parallel parallel(1);
  ImplicitStepper stepper(model, tight(), parallel);
  FemState state = FemState::atRest(*model);
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0, 0.5);
  for (int i = 0; i < state.velocities.size(); ++i)
    state.velocities[i] = n(rng);
  NodeConstraints constraints(model->nodeCount());
  constraints.prescribeVelocity(0, Eigen::Vector3d::Zero());
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(3 * model->nodeCount());
  const std::vector<int> nodes = {0, 7, 3, 44, model->nodeCount() - 1};
  for (int k = 0; k < 5; ++k) {
    ASSERT_FALSE(isFatal(stepper.step(state, constraints, zero).health));
    const Eigen::VectorXd rows = stepper.internalForcesAt(nodes);  // before internalForces()
    const Eigen::VectorXd& whole = stepper.internalForces();
    for (int node : nodes) {
      for (int a = 0; a < 3; ++a)
        EXPECT_EQ(rows(3 * node + a), whole(3 * node + a)) << "step " << k << " node " << node;
    }
  }
}

TEST(ImplicitStepper, TotalEnergyNeverRisesWithDamping) {
  auto model = beamModel();
  Parallel parallel(1);
  ImplicitStepper stepper(model, tight(), parallel);
  FemState state = FemState::atRest(*model);
  for (int i = 0; i < model->nodeCount(); ++i) {  // stretch 20 % along x and shear a little
    state.positions[3 * i] *= 1.2;
    state.positions[3 * i + 1] += 0.05 * state.positions[3 * i];
  }
  NodeConstraints constraints(model->nodeCount());
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(3 * model->nodeCount());
  double kinetic = 0, previous_total = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 200; ++k) {
    const StepReport r = stepper.step(state, constraints, zero);
    ASSERT_FALSE(isFatal(r.health)) << r.message;
    const double total = r.elastic_energy + kinetic;  // both at the start of step k
    EXPECT_LE(total, previous_total * (1 + 1e-9)) << "step " << k;
    previous_total = total;
    kinetic = r.kinetic_energy;
  }
  EXPECT_LT(previous_total, 0.05 * stepper.computeElasticForces(state) + previous_total);
}

TEST(ImplicitStepper, InvertedTetRecovers) {
  // One tet with its apex pushed through the opposite face.
  auto mesh = std::make_shared<TetMesh>(
      std::vector<Eigen::Vector3d>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
      std::vector<Tet>{{0, 1, 2, 3}});
  auto model = FemModel::create(mesh, Material{}).value();
  Parallel parallel(1);
  ImplicitStepper stepper(model, tight(), parallel);
  FemState state = FemState::atRest(*model);
  state.positions.segment<3>(9) = Eigen::Vector3d(0.2, 0.2, -0.3);
  EXPECT_LT(
      sixSignedVolume(state.position(0), state.position(1), state.position(2), state.position(3)),
      0);
  NodeConstraints constraints(model->nodeCount());
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(12);
  for (int k = 0; k < 300; ++k)
    ASSERT_FALSE(isFatal(stepper.step(state, constraints, zero).health));
  const double six_volume =
      sixSignedVolume(state.position(0), state.position(1), state.position(2), state.position(3));
  EXPECT_NEAR(six_volume, 1.0, 0.02);  // back to its rest volume (6V = 1)
}

TEST(ImplicitStepper, ProjectionHoldsFixedAndDrivesPrescribedNodes) {
  auto model = beamModel();
  Parallel parallel(1);
  const SolverSettings settings = tight();
  ImplicitStepper stepper(model, settings, parallel);
  FemState state = FemState::atRest(*model);
  NodeConstraints constraints(model->nodeCount());
  const Eigen::VectorXd f = gravityForces(*model, Eigen::Vector3d(0, 0, -9.81));
  const Eigen::Vector3d drive(0, 0.3, 0);
  for (int k = 0; k < 20; ++k) {
    constraints.reset(model->nodeCount());
    for (int i = 0; i < model->nodeCount(); ++i) {
      const double x = model->mesh().restPositions()[static_cast<size_t>(i)].x();
      if (x < 1e-9) constraints.prescribeVelocity(i, Eigen::Vector3d::Zero());
      if (x > 4 - 1e-9) constraints.prescribeVelocity(i, drive);
    }
    const FemState before = state;
    ASSERT_FALSE(isFatal(stepper.step(state, constraints, f).health));
    for (int i = 0; i < model->nodeCount(); ++i) {
      const double x = model->mesh().restPositions()[static_cast<size_t>(i)].x();
      if (x < 1e-9) {
        EXPECT_EQ(state.position(i), before.position(i));
      } else if (x > 4 - 1e-9) {
        EXPECT_LT((state.position(i) - before.position(i) - settings.time_step * drive).norm(),
                  1e-14);
      }
    }
  }
  // The free middle sags under gravity.
  EXPECT_LT(state.positions.minCoeff(), -1e-4);
}

TEST(ImplicitStepper, DirectionConstraintFixesOnlyTheNormalComponent) {
  // A body pulled along x with its bottom face held at z = 0 (a frictionless floor): the bottom
  // keeps z exactly and the whole body still accelerates along x at 1 m/s^2.
  auto model = beamModel();
  Parallel parallel(1);
  const SolverSettings settings = tight();
  ImplicitStepper stepper(model, settings, parallel);
  FemState state = FemState::atRest(*model);
  NodeConstraints constraints(model->nodeCount());
  for (int i = 0; i < model->nodeCount(); ++i) {
    if (model->mesh().restPositions()[static_cast<size_t>(i)].z() < 1e-9) {
      constraints.prescribeDirection(i, Eigen::Vector3d::UnitZ(), 0.0);
    }
  }
  const Eigen::VectorXd f = gravityForces(*model, Eigen::Vector3d(1.0, 0, 0));
  const int steps = 10;
  for (int k = 0; k < steps; ++k)
    ASSERT_FALSE(isFatal(stepper.step(state, constraints, f).health));
  for (int i = 0; i < model->nodeCount(); ++i) {
    if (model->mesh().restPositions()[static_cast<size_t>(i)].z() < 1e-9) {
      EXPECT_NEAR(state.position(i).z(), 0.0, 1e-12);
    }
    EXPECT_NEAR(state.velocity(i).x(), steps * settings.time_step * 1.0, 1e-8);
  }
}

// The constrained nodes, fully or along a direction, in ascending order, and none after a reset;
// the list a caller passes in is replaced, not appended to.
TEST(ImplicitStepper, ConstrainedNodesListsHeldAndDirectionNodesAscending) {
  NodeConstraints constraints(6);
  constraints.prescribeVelocity(4, Eigen::Vector3d(1, 0, 0));
  constraints.prescribeDirection(1, Eigen::Vector3d::UnitZ(), 0.0);
  std::vector<int> nodes = {7, 7, 7};
  constraints.constrainedNodes(nodes);
  EXPECT_EQ(nodes, (std::vector<int>{1, 4}));
  EXPECT_EQ(static_cast<int>(nodes.size()), constraints.constrainedCount());
  constraints.reset(6);
  constraints.constrainedNodes(nodes);
  EXPECT_TRUE(nodes.empty());
}

FemState twistedRun(int threads, LinearSolverKind kind, int steps = 15,
                    PreconditionerKind preconditioner = PreconditionerKind::kBlockJacobi,
                    std::shared_ptr<const FemModel> model = beamModel(),
                    std::int64_t* split_calls = nullptr) {
  Parallel parallel(threads);
  SolverSettings settings;
  settings.linear_solver = kind;
  settings.preconditioner = preconditioner;
  settings.tolerance = 1e-8;
  ImplicitStepper stepper(model, settings, parallel);
  FemState state = FemState::atRest(*model);
  NodeConstraints constraints(model->nodeCount());
  const Eigen::VectorXd f = gravityForces(*model, Eigen::Vector3d(0, 0, -9.81));
  const double omega = 2.0;  // rad/s about the beam axis (x), through (y, z) = (0.5, 0.5)
  for (int k = 0; k < steps; ++k) {
    constraints.reset(model->nodeCount());
    for (int i = 0; i < model->nodeCount(); ++i) {
      const Eigen::Vector3d p = state.position(i);
      if (model->mesh().restPositions()[static_cast<size_t>(i)].x() < 1e-9)
        constraints.prescribeVelocity(i, Eigen::Vector3d::Zero());
      if (model->mesh().restPositions()[static_cast<size_t>(i)].x() > 4 - 1e-9) {
        const Eigen::Vector3d r = p - Eigen::Vector3d(p.x(), 0.5, 0.5);
        const Eigen::AngleAxisd turn(omega * settings.time_step, Eigen::Vector3d::UnitX());
        constraints.prescribeVelocity(i, (turn * r - r) / settings.time_step);
      }
    }
    const StepReport r = stepper.step(state, constraints, f);
    EXPECT_EQ(r.health, StepHealth::kOk) << r.message;
    if (kind == LinearSolverKind::kConjugateGradient) {
      EXPECT_GT(r.solve.iterations, 0);
    }
  }
  if (split_calls != nullptr) *split_calls = parallel.splitCalls();
  return state;
}

TEST(ImplicitStepper, SameResultForAnyThreadCount) {
  // 5184 tets and 1225 nodes: above every kernel's grain, so the 2-thread run really splits.
  auto model =
      FemModel::create(
          std::make_shared<TetMesh>(
              makeBoxTetMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(4, 1, 1), 24, 6, 6).value()),
          Material{})
          .value();
  std::int64_t serial_splits = -1, parallel_splits = -1;
  const FemState one = twistedRun(1, LinearSolverKind::kConjugateGradient, 5,
                                  PreconditionerKind::kBlockJacobi, model, &serial_splits);
  const FemState two = twistedRun(2, LinearSolverKind::kConjugateGradient, 5,
                                  PreconditionerKind::kBlockJacobi, model, &parallel_splits);
  EXPECT_EQ(serial_splits, 0);
  EXPECT_GT(parallel_splits, 0) << "the 2-thread run must have split its loops";
  EXPECT_TRUE(one.positions == two.positions)
      << "max diff " << (one.positions - two.positions).cwiseAbs().maxCoeff();
}

TEST(ImplicitStepper, JacobiAndBlockJacobiReachTheSameSolution) {
  const FemState block = twistedRun(1, LinearSolverKind::kConjugateGradient);
  const FemState diagonal =
      twistedRun(1, LinearSolverKind::kConjugateGradient, 15, PreconditionerKind::kJacobi);
  const FemState start = FemState::atRest(*beamModel());
  EXPECT_LT((block.positions - diagonal.positions).norm(),
            1e-6 * (block.positions - start.positions).norm());
}

TEST(ImplicitStepper, ConjugateGradientStuckFarAboveToleranceIsFatal) {
  auto model = beamModel();
  Parallel parallel(1);
  SolverSettings settings = tight();
  settings.max_iterations = 1;  // cannot reach 1e-10 in one iteration
  ImplicitStepper stepper(model, settings, parallel);
  FemState state = FemState::atRest(*model);
  NodeConstraints constraints(model->nodeCount());
  for (int i = 0; i < model->nodeCount(); ++i) {
    if (model->mesh().restPositions()[static_cast<size_t>(i)].x() < 1e-9)
      constraints.prescribeVelocity(i, Eigen::Vector3d::Zero());
  }
  Eigen::VectorXd f(3 * model->nodeCount());
  for (int i = 0; i < model->nodeCount(); ++i)
    f.segment<3>(3 * i) =
        Eigen::Vector3d(0, 0, -9.81 * model->nodeMasses()[static_cast<size_t>(i)]);
  const StepReport r = stepper.step(state, constraints, f);
  EXPECT_EQ(r.health, StepHealth::kSolverFailed);
  EXPECT_NE(r.message.find("did not converge"), std::string::npos) << r.message;
}

TEST(ImplicitStepper, CholmodAgreesWithConjugateGradient) {
  const FemState cg = twistedRun(1, LinearSolverKind::kConjugateGradient);
  const FemState direct = twistedRun(1, LinearSolverKind::kCholmod);
  const FemState start = FemState::atRest(*beamModel());
  const double motion = (cg.positions - start.positions).norm();
  EXPECT_LT((cg.positions - direct.positions).norm(), 1e-6 * motion);
}

TEST(ImplicitStepper, NonFiniteInputIsReportedNotPropagatedSilently) {
  auto model = beamModel();
  Parallel parallel(1);
  ImplicitStepper stepper(model, tight(), parallel);
  FemState state = FemState::atRest(*model);
  NodeConstraints constraints(model->nodeCount());
  Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * model->nodeCount());
  f[7] = std::numeric_limits<double>::quiet_NaN();
  const StepReport r = stepper.step(state, constraints, f);
  EXPECT_EQ(r.health, StepHealth::kNonFinite);
  EXPECT_FALSE(r.message.empty());
}

TEST(ImplicitStepper, StagesDrivenByTheCallerAreTheStepBitForBit) {
  // prepare, a solve of prepared() into a vector of the caller's, finish: what FemBody and the
  // islands do. The same bits as step(), warm starts and internal forces included.
  auto model = beamModel();
  Parallel parallel(1);
  SolverSettings settings;  // the default tolerance: CG stops early, so warm starts matter
  ImplicitStepper whole(model, settings, parallel), staged(model, settings, parallel);
  FemState a = FemState::atRest(*model), b = a;
  NodeConstraints constraints(model->nodeCount());
  for (int i = 0; i < model->nodeCount(); ++i) {
    if (model->mesh().restPositions()[static_cast<size_t>(i)].x() < 1e-9)
      constraints.prescribeVelocity(i, Eigen::Vector3d::Zero());
  }
  const Eigen::VectorXd f = gravityForces(*model, Eigen::Vector3d(0, 0, -9.81));
  ProjectedCg cg;
  for (int k = 0; k < 8; ++k) {
    const StepReport r = whole.step(a, constraints, f);
    StepReport s = staged.prepare(b, constraints, f, settings.time_step);
    ASSERT_FALSE(isFatal(s.health));
    const PreparedSystem system = staged.prepared();
    Eigen::VectorXd v = *system.v;
    s.solve = cg.solve(*system.op, *system.constraints, *system.b, *system.settings, v);
    staged.finish(b, v, s);
    ASSERT_EQ(r.health, s.health);
    EXPECT_EQ(r.solve.iterations, s.solve.iterations);
    EXPECT_EQ(r.kinetic_energy, s.kinetic_energy);
    ASSERT_TRUE(a.positions == b.positions) << "step " << k;
    ASSERT_TRUE(a.velocities == b.velocities) << "step " << k;
    ASSERT_TRUE(whole.internalForces() == staged.internalForces()) << "step " << k;
  }
}

TEST(ImplicitStepper, PrepareWithNonFiniteForcesEndsTheStepBeforeTheStateIsTouched) {
  auto model = beamModel();
  Parallel parallel(1);
  ImplicitStepper stepper(model, tight(), parallel);
  FemState state = FemState::atRest(*model);
  state.velocities.setConstant(0.25);
  const FemState start = state;
  NodeConstraints constraints(model->nodeCount());
  Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * model->nodeCount());
  f[4] = std::numeric_limits<double>::infinity();
  const StepReport r = stepper.prepare(state, constraints, f, 0.01);
  EXPECT_EQ(r.health, StepHealth::kNonFinite);
  EXPECT_NE(r.message.find("external forces"), std::string::npos) << r.message;
  EXPECT_TRUE(state.positions == start.positions);
  EXPECT_TRUE(state.velocities == start.velocities);
}

TEST(ImplicitStepper, BlowUpIsDetected) {
  auto model = beamModel();
  Parallel parallel(1);
  SolverSettings settings = tight();
  settings.max_speed = 10;
  ImplicitStepper stepper(model, settings, parallel);
  FemState state = FemState::atRest(*model);
  state.velocities.setConstant(50.0);
  NodeConstraints constraints(model->nodeCount());
  const StepReport r =
      stepper.step(state, constraints, Eigen::VectorXd::Zero(3 * model->nodeCount()));
  EXPECT_EQ(r.health, StepHealth::kBlowUp);
  EXPECT_NE(r.message.find("max_speed"), std::string::npos);
}

}  // namespace
}  // namespace torsion

namespace torsion {
namespace {

// CHOLMOD's matrix is built from the operator's blocks; both must agree with an element-by-element
// product (corotated_element.h), and the operator's products and diagonal blocks with the matrix.
TEST(SystemOperator, ProductsAndDiagonalBlocksMatchTheAssembledMatrix) {
  auto model = beamModel();
  Parallel parallel(2);
  SystemOperator op(model, parallel);
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0, 1);
  for (auto& R : op.mutableRotations()) {
    R = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
  }
  op.setCoefficients(1.01, 1e-4);
  CholmodSolver cholmod;
  const NodeConstraints none(model->nodeCount());
  const Eigen::SparseMatrix<double> lower = cholmod.assemble(op, none);
  const Eigen::MatrixXd L = Eigen::MatrixXd(lower);
  const Eigen::MatrixXd A = L + L.transpose() - Eigen::MatrixXd(L.diagonal().asDiagonal());

  Eigen::VectorXd y(3 * model->nodeCount());
  for (int i = 0; i < y.size(); ++i)
    y[i] = n(rng);
  Eigen::VectorXd Ay;
  op.multiply(y, Ay);
  EXPECT_LT((Ay - A * y).norm(), 1e-10 * Ay.norm());

  // Reference: A y = c_m M y - c_k sum_e df_e(y_e), tet by tet.
  Eigen::VectorXd reference(y.size());
  for (int i = 0; i < model->nodeCount(); ++i)
    reference.segment<3>(3 * i) =
        1.01 * model->nodeMasses()[static_cast<size_t>(i)] * y.segment<3>(3 * i);
  for (int t = 0; t < model->elementCount(); ++t) {
    const int* nodes = model->elementNodes().data() + 4 * t;
    std::array<Eigen::Vector3d, 4> dx;
    for (size_t a = 0; a < 4; ++a)
      dx[a] = y.segment<3>(3 * nodes[a]);
    const std::array<Eigen::Vector3d, 4> df = corotatedForceDifferential(
        dx, op.rotations()[static_cast<size_t>(t)], model->tetRestData()[static_cast<size_t>(t)],
        model->material().mu(), model->material().lambda());
    for (size_t a = 0; a < 4; ++a)
      reference.segment<3>(3 * nodes[a]) -= 1e-4 * df[a];
  }
  EXPECT_LT((A * y - reference).norm(), 1e-10 * reference.norm());

  std::vector<Eigen::Matrix3d> blocks;
  op.diagonalBlocks(blocks);
  for (int i = 0; i < model->nodeCount(); ++i) {
    EXPECT_LT((blocks[static_cast<size_t>(i)] - A.block<3, 3>(3 * i, 3 * i)).norm(),
              1e-10 * A.norm())
        << "node " << i;
  }
}

}  // namespace
}  // namespace torsion
