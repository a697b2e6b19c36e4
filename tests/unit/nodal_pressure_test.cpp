// The average nodal pressure tet4 (fem/nodal_pressure.h) against its defining energy, written out
// here independently: forces are its gradient, the system's stiffness (CG products, diagonal
// blocks, CHOLMOD's matrix) its Hessian at the step's rotations; a rigid motion changes nothing
// but the frame; a homogeneous strain gives the plain tet4's answer; any thread count gives the
// same bits.
#include "torsion/fem/nodal_pressure.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <random>

#include "torsion/mesh/box_mesh.h"
#include "torsion/solve/cholmod_solver.h"
#include "torsion/solve/implicit_stepper.h"

namespace torsion {
namespace {

Material nearlyIncompressible(VolumetricStrain volumetric = VolumetricStrain::kNodalAverage) {
  Material m;
  m.youngs_modulus = 1e5;
  m.poisson_ratio = 0.45;
  m.volumetric_strain = volumetric;
  return m;
}

std::shared_ptr<const FemModel> blockModel(const Material& material) {
  auto mesh = std::make_shared<TetMesh>(
      makeBoxTetMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 2), 2, 2, 3).value());
  return FemModel::create(mesh, material).value();
}

// The rest positions moved by a random distortion of about 5 % of a cell, then turned by a large
// rotation and shifted: rotations far from I exercise the corotation.
Eigen::VectorXd deformed(const FemModel& model, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.025, 0.025);
  const Eigen::Matrix3d Q =
      Eigen::AngleAxisd(0.9, Eigen::Vector3d(1, 2, -0.5).normalized()).toRotationMatrix();
  Eigen::VectorXd x(3 * model.nodeCount());
  for (int i = 0; i < model.nodeCount(); ++i) {
    const Eigen::Vector3d p = model.mesh().restPositions()[static_cast<size_t>(i)] +
                              Eigen::Vector3d(u(rng), u(rng), u(rng));
    x.segment<3>(3 * i) = Q * p + Eigen::Vector3d(0.3, -1, 2);
  }
  return x;
}

// E = sum_e V_e mu |dev eps_e|^2 + sum_n V_n kappa / 2 theta_n^2 at positions x with the
// rotations R held fixed (nodal_pressure.h), from the definitions alone.
double referenceEnergy(const FemModel& model, const std::vector<Eigen::Matrix3d>& R,
                       const Eigen::VectorXd& x) {
  const double mu = model.material().mu(), kappa = model.material().bulkModulus();
  std::vector<double> node_sum(static_cast<size_t>(model.nodeCount()), 0.0);
  std::vector<double> node_volume(static_cast<size_t>(model.nodeCount()), 0.0);
  double energy = 0;
  for (int t = 0; t < model.elementCount(); ++t) {
    const Tet& tet = model.mesh().tets()[static_cast<size_t>(t)];
    const TetRestData& rest = model.tetRestData()[static_cast<size_t>(t)];
    Eigen::Matrix3d Ds;
    for (int k = 0; k < 3; ++k)
      Ds.col(k) = x.segment<3>(3 * tet[static_cast<size_t>(k + 1)]) - x.segment<3>(3 * tet[0]);
    const Eigen::Matrix3d RtF =
        R[static_cast<size_t>(t)].transpose() * Ds * rest.rest_shape_inverse;
    const Eigen::Matrix3d eps = 0.5 * (RtF + RtF.transpose()) - Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d dev = eps - eps.trace() / 3 * Eigen::Matrix3d::Identity();
    energy += rest.volume * mu * dev.squaredNorm();
    for (int n : tet) {
      node_sum[static_cast<size_t>(n)] += rest.volume / 4 * eps.trace();
      node_volume[static_cast<size_t>(n)] += rest.volume / 4;
    }
  }
  for (size_t n = 0; n < node_sum.size(); ++n) {
    const double theta = node_sum[n] / node_volume[n];
    energy += node_volume[n] * kappa / 2 * theta * theta;
  }
  return energy;
}

struct Evaluated {
  std::shared_ptr<const FemModel> model;
  Parallel parallel{1};
  std::unique_ptr<ImplicitStepper> stepper;
  FemState state;
  double energy = 0;

  explicit Evaluated(const Material& material, unsigned seed = 7)
      : model(blockModel(material)),
        stepper(std::make_unique<ImplicitStepper>(model, SolverSettings{}, parallel)),
        state(FemState::atRest(*model)) {
    state.positions = deformed(*model, seed);
    energy = stepper->computeElasticForces(state);
  }
  const std::vector<Eigen::Matrix3d>& rotations() const { return stepper->system().rotations(); }
};

TEST(NodalPressure, ForcesAreTheGradientOfTheEnergyAtTheStepsRotations) {
  Evaluated e(nearlyIncompressible());
  const double reference = referenceEnergy(*e.model, e.rotations(), e.state.positions);
  EXPECT_NEAR(e.energy, reference, 1e-12 * reference);
  ASSERT_GT(reference, 0);
  const Eigen::VectorXd& f = e.stepper->elasticForces();
  const double h = 1e-6, scale = f.cwiseAbs().maxCoeff();
  for (int i = 0; i < f.size(); ++i) {
    Eigen::VectorXd plus = e.state.positions, minus = e.state.positions;
    plus[i] += h;
    minus[i] -= h;
    // The energy is quadratic at fixed rotations: the central difference is exact but round-off.
    const double gradient = (referenceEnergy(*e.model, e.rotations(), plus) -
                             referenceEnergy(*e.model, e.rotations(), minus)) /
                            (2 * h);
    EXPECT_NEAR(f[i], -gradient, 1e-6 * scale) << "dof " << i;
  }
}

// z^T K y from four energies (exact for a quadratic), against every form the solver uses.
TEST(NodalPressure, StiffnessIsTheHessianOfTheEnergyInEverySolverForm) {
  Evaluated e(nearlyIncompressible());
  SystemOperator system(e.model, e.parallel);
  system.mutableRotations() = e.rotations();
  system.setCoefficients(0.0, 1.0);  // A = K
  const int dofs = 3 * e.model->nodeCount();
  CholmodSolver cholmod;
  const Eigen::SparseMatrix<double> lower =
      cholmod.assemble(system, NodeConstraints(e.model->nodeCount()));
  const Eigen::SparseMatrix<double> full =
      Eigen::SparseMatrix<double>(lower.selfadjointView<Eigen::Lower>());
  std::mt19937 rng(3);
  std::normal_distribution<double> n01;
  auto hessian = [&](const Eigen::VectorXd& y, const Eigen::VectorXd& z) {
    const Eigen::VectorXd& x = e.state.positions;
    auto E = [&](const Eigen::VectorXd& p) { return referenceEnergy(*e.model, e.rotations(), p); };
    return (E(x + y + z) - E(x + y - z) - E(x - y + z) + E(x - y - z)) / 4;
  };
  Eigen::VectorXd product;
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd y(dofs), z(dofs);
    for (int i = 0; i < dofs; ++i) {
      y[i] = 1e-3 * n01(rng);
      z[i] = 1e-3 * n01(rng);
    }
    const double reference = hessian(y, z);
    const double bound = 1e-7 * std::sqrt(hessian(y, y) * hessian(z, z));
    system.multiplyStiffness(y, product);
    EXPECT_NEAR(z.dot(product), reference, bound) << "CG product, trial " << trial;
    EXPECT_NEAR(z.dot(full * y), reference, bound) << "CHOLMOD matrix, trial " << trial;
  }
  // Diagonal blocks (block-Jacobi preconditioner): e_i^T K e_j within each node.
  std::vector<Eigen::Matrix3d> blocks;
  system.diagonalBlocks(blocks);
  for (int node = 0; node < e.model->nodeCount(); node += 5) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        Eigen::VectorXd y = Eigen::VectorXd::Zero(dofs), z = Eigen::VectorXd::Zero(dofs);
        y[3 * node + c] = 1e-3;
        z[3 * node + r] = 1e-3;
        const double reference = hessian(y, z) / 1e-6;
        EXPECT_NEAR(blocks[static_cast<size_t>(node)](r, c), reference,
                    1e-6 * blocks[static_cast<size_t>(node)].norm())
            << "node " << node << " (" << r << ", " << c << ")";
      }
    }
  }
}

// A homogeneous strain has the same trace in every tet, so every node average equals it and the
// pressure is the plain tet4's: forces identical to round-off.
TEST(NodalPressure, HomogeneousStrainGivesThePlainTet4Forces) {
  Material nodal = nearlyIncompressible(),
           plain = nearlyIncompressible(VolumetricStrain::kPerElement);
  auto nodal_model = blockModel(nodal), plain_model = blockModel(plain);
  Parallel parallel(1);
  ImplicitStepper nodal_stepper(nodal_model, SolverSettings{}, parallel);
  ImplicitStepper plain_stepper(plain_model, SolverSettings{}, parallel);
  FemState state = FemState::atRest(*nodal_model);
  const Eigen::Matrix3d F =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY()).toRotationMatrix() *
      (Eigen::Matrix3d() << 1.03, 0.01, 0, 0.01, 0.97, 0.02, 0, 0.02, 1.05).finished();
  for (int i = 0; i < nodal_model->nodeCount(); ++i)
    state.positions.segment<3>(3 * i) =
        F * nodal_model->mesh().restPositions()[static_cast<size_t>(i)];
  FemState plain_state = state;
  const double nodal_energy = nodal_stepper.computeElasticForces(state);
  const double plain_energy = plain_stepper.computeElasticForces(plain_state);
  EXPECT_NEAR(nodal_energy, plain_energy, 1e-12 * plain_energy);
  const Eigen::VectorXd& a = nodal_stepper.elasticForces();
  const Eigen::VectorXd& b = plain_stepper.elasticForces();
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-10 * b.cwiseAbs().maxCoeff());
}

TEST(NodalPressure, RigidMotionOnlyTurnsTheForces) {
  Evaluated e(nearlyIncompressible());
  const Eigen::Matrix3d Q =
      Eigen::AngleAxisd(2.1, Eigen::Vector3d(-0.3, 1, 0.2).normalized()).toRotationMatrix();
  FemState turned = e.state;
  for (int i = 0; i < e.model->nodeCount(); ++i)
    turned.positions.segment<3>(3 * i) = Q * e.state.position(i) + Eigen::Vector3d(5, 0, -1);
  ImplicitStepper other(e.model, SolverSettings{}, e.parallel);
  const double energy = other.computeElasticForces(turned);
  EXPECT_NEAR(energy, e.energy, 1e-9 * e.energy);
  const Eigen::VectorXd& f = e.stepper->elasticForces();
  const Eigen::VectorXd& g = other.elasticForces();
  for (int i = 0; i < e.model->nodeCount(); ++i)
    EXPECT_LT((g.segment<3>(3 * i) - Q * f.segment<3>(3 * i)).norm(), 1e-6 * f.norm()) << i;
  // At rest, anywhere and turned any way: no force.
  FemState rest = FemState::atRest(*e.model);
  for (int i = 0; i < e.model->nodeCount(); ++i)
    rest.positions.segment<3>(3 * i) = Q * rest.position(i) + Eigen::Vector3d(1, 2, 3);
  EXPECT_LT(other.computeElasticForces(rest), 1e-20);
  EXPECT_LT(other.elasticForces().cwiseAbs().maxCoeff(), 1e-9);
}

TEST(NodalPressure, ForcesAndProductsAreTheSameForAnyThreadCount) {
  auto model =
      FemModel::create(
          std::make_shared<TetMesh>(
              makeBoxTetMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(4, 1, 1), 24, 6, 6).value()),
          nearlyIncompressible())
          .value();  // 5184 tets: several chunks per pass
  Eigen::VectorXd forces[2], products[2];
  std::vector<Eigen::Matrix3d> blocks[2];
  for (int k = 0; k < 2; ++k) {
    Parallel parallel(k == 0 ? 1 : 2);
    ImplicitStepper stepper(model, SolverSettings{}, parallel);
    FemState state = FemState::atRest(*model);
    state.positions = deformed(*model, 11);
    stepper.computeElasticForces(state);
    forces[k] = stepper.elasticForces();
    const Eigen::VectorXd y = deformed(*model, 12) - deformed(*model, 13);
    stepper.system().multiplyStiffness(y, products[k]);
    stepper.system().diagonalBlocks(blocks[k]);
  }
  EXPECT_TRUE(forces[0] == forces[1]);
  EXPECT_TRUE(products[0] == products[1]);
  EXPECT_TRUE(blocks[0] == blocks[1]);
}

// The implicit step with both linear solvers: a beam clamped at one end sags under gravity for
// 10 steps of 0.01 s at nu = 0.49; CG (solved tightly) and CHOLMOD land on the same positions.
TEST(NodalPressure, ConjugateGradientAndCholmodTakeTheSameSteps) {
  Material material = nearlyIncompressible();
  material.poisson_ratio = 0.49;
  auto model =
      FemModel::create(
          std::make_shared<TetMesh>(
              makeBoxTetMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(4, 1, 1), 8, 2, 2).value()),
          material)
          .value();
  NodeConstraints constraints(model->nodeCount());
  Eigen::VectorXd gravity(3 * model->nodeCount());
  for (int i = 0; i < model->nodeCount(); ++i) {
    gravity.segment<3>(3 * i) =
        model->nodeMasses()[static_cast<size_t>(i)] * Eigen::Vector3d(0, 0, -9.81);
    if (model->mesh().restPositions()[static_cast<size_t>(i)].x() < 1e-9)
      constraints.prescribeVelocity(i, Eigen::Vector3d::Zero());
  }
  FemState end[2];
  for (int k = 0; k < 2; ++k) {
    SolverSettings settings;
    settings.linear_solver =
        k == 0 ? LinearSolverKind::kConjugateGradient : LinearSolverKind::kCholmod;
    settings.tolerance = 1e-10;
    settings.max_iterations = 5000;
    Parallel parallel(1);
    ImplicitStepper stepper(model, settings, parallel);
    end[k] = FemState::atRest(*model);
    for (int step = 0; step < 10; ++step) {
      const StepReport r = stepper.step(end[k], constraints, gravity);
      ASSERT_EQ(r.health, StepHealth::kOk) << r.message;
    }
  }
  const double motion = (end[0].positions - FemState::atRest(*model).positions).norm();
  ASSERT_GT(motion, 1e-3);
  EXPECT_LT((end[0].positions - end[1].positions).norm(), 1e-6 * motion);
}

TEST(NodalPressure, Tet10BodiesRefuseIt) {
  auto mesh = std::make_shared<TetMesh>(
      makeBoxTetMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1), 1, 1, 1).value());
  Result<std::shared_ptr<const FemModel>> model =
      FemModel::create(mesh, nearlyIncompressible(), ElementKind::kTet10);
  ASSERT_FALSE(model.ok());
  EXPECT_NE(model.error().message.find("tet4 option"), std::string::npos) << model.error().message;
}

}  // namespace
}  // namespace torsion
