// The system operator's two kernel builds (baseline and AVX2 + FMA, system_operator.h): the same
// K and the same products to rounding, for tet4 and tet10; and the tet4 blocks against the
// element's own force differential. (The tet10 blocks are checked against the element
// differentials in quadratic_mesh_test.cpp.)

#include "solve/system_operator_kernels.h"  // white box: extension/src

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstring>
#include <limits>
#include <random>

#include "torsion/fem/corotated_element.h"
#include "torsion/fem/factored_tet_hessian.h"
#include "torsion/fem/hyperelastic.h"
#include "torsion/fem/polar_rotation.h"
#include "torsion/mesh/box_mesh.h"
#include "torsion/solve/implicit_stepper.h"
#include "torsion/solve/system_operator.h"

namespace torsion {
namespace {

std::shared_ptr<const FemModel> beam(ElementKind element) {
  auto mesh = std::make_shared<const TetMesh>(
      makeBoxTetMesh(Eigen::Vector3d::Zero(), {4, 1, 1}, 4, 2, 2).value());
  return FemModel::create(mesh, Material{}, element).value();
}

void randomRotations(SystemOperator& op, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  for (auto& R : op.mutableRotations())
    R = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}

Eigen::VectorXd randomVector(int size, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  Eigen::VectorXd y(size);
  for (int i = 0; i < size; ++i)
    y[i] = n(rng);
  return y;
}

// Products and blocks of both builds for one model; on a CPU without AVX2 both runs are the
// baseline build and agree exactly.
void expectBuildsAgree(ElementKind element) {
  auto model = beam(element);
  Parallel parallel(1);
  SystemOperator best(model, parallel), baseline(model, parallel);
  baseline.useBaselineKernels(true);
  EXPECT_STREQ(baseline.kernelPath(), "sse2");
  EXPECT_STREQ(best.kernelPath(), SystemOperator::bestKernelPath());
  std::mt19937 rng(3);
  randomRotations(best, rng);
  baseline.mutableRotations() = best.rotations();
  best.setCoefficients(1.01, 1e-4);
  baseline.setCoefficients(1.01, 1e-4);
  const Eigen::VectorXd y = randomVector(3 * model->nodeCount(), rng);
  Eigen::VectorXd a, b;
  best.multiply(y, a);
  baseline.multiply(y, b);
  EXPECT_LT((a - b).norm(), 1e-13 * b.norm());
  const auto& blocks_a = best.stiffnessBlocks();
  const auto& blocks_b = baseline.stiffnessBlocks();
  ASSERT_EQ(blocks_a.size(), blocks_b.size());
  double largest = 0, difference = 0;
  for (size_t s = 0; s < blocks_a.size(); ++s) {
    largest = std::max(largest, blocks_b[s].cwiseAbs().maxCoeff());
    difference = std::max(difference, (blocks_a[s] - blocks_b[s]).cwiseAbs().maxCoeff());
  }
  EXPECT_LE(difference, 1e-13 * largest);
}

TEST(SystemOperatorKernels, BothBuildsGiveTheSameTet4MatrixAndProducts) {
  expectBuildsAgree(ElementKind::kTet4);
}

TEST(SystemOperatorKernels, BothBuildsGiveTheSameTet10MatrixAndProducts) {
  expectBuildsAgree(ElementKind::kTet10);
}

// K y from the blocks equals minus the sum of the elements' force differentials, for each build.
TEST(SystemOperatorKernels, Tet4ProductsMatchTheElementDifferentialsInEitherBuild) {
  auto model = beam(ElementKind::kTet4);
  Parallel parallel(2);
  for (bool baseline : {false, true}) {
    SystemOperator op(model, parallel);
    op.useBaselineKernels(baseline);
    std::mt19937 rng(11);
    randomRotations(op, rng);
    const Eigen::VectorXd y = randomVector(3 * model->nodeCount(), rng);
    Eigen::VectorXd reference = Eigen::VectorXd::Zero(y.size());
    const double mu = model->material().mu(), lambda = model->material().lambda();
    for (int e = 0; e < model->elementCount(); ++e) {
      const int* nodes = model->elementNodes().data() + 4 * e;
      std::array<Eigen::Vector3d, 4> dx;
      for (size_t a = 0; a < 4; ++a)
        dx[a] = y.segment<3>(3 * nodes[a]);
      const auto df =
          corotatedForceDifferential(dx, op.rotations()[static_cast<size_t>(e)],
                                     model->tetRestData()[static_cast<size_t>(e)], mu, lambda);
      for (size_t a = 0; a < 4; ++a)
        reference.segment<3>(3 * nodes[a]) -= df[a];
    }
    Eigen::VectorXd Ky;
    op.multiplyStiffness(y, Ky);
    EXPECT_LT((Ky - reference).norm(), 1e-12 * reference.norm()) << op.kernelPath();
  }
}

// The kernel builds this machine runs: baseline, and AVX2 + FMA where the CPU has both.
std::vector<const system_kernels::KernelTable*> kernelBuilds() {
  std::vector<const system_kernels::KernelTable*> builds = {&system_kernels::genericKernels()};
  if (std::strcmp(SystemOperator::bestKernelPath(), "avx2+fma") == 0)
    builds.push_back(system_kernels::avx2Kernels());
  return builds;
}

const Eigen::Matrix3d kTurn =
    Eigen::Quaterniond(0.9, 0.3, -0.2, 0.4).normalized().toRotationMatrix();

// The model's rest positions mapped by `A`, plus normal noise of deviation `noise` (seeded), flat.
std::vector<double> deformedPositions(const FemModel& model, const Eigen::Matrix3d& A, double noise,
                                      unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0, 1);
  std::vector<double> positions;
  for (const Eigen::Vector3d& X : model.mesh().restPositions()) {
    const Eigen::Vector3d x = A * X + noise * Eigen::Vector3d(n(rng), n(rng), n(rng));
    positions.insert(positions.end(), x.data(), x.data() + 3);
  }
  return positions;
}

std::array<Eigen::Vector3d, 4> tetCorners(const std::vector<double>& positions,
                                          const std::vector<int>& nodes, size_t t) {
  std::array<Eigen::Vector3d, 4> x;
  for (size_t a = 0; a < 4; ++a)
    x[a] = Eigen::Map<const Eigen::Vector3d>(positions.data() + 3 * nodes[4 * t + a]);
  return x;
}

// A kernel's 12 forces of tet t against the element function's, relative to their size.
void expectForcesNear(const std::vector<double>& forces, size_t t,
                      const std::array<Eigen::Vector3d, 4>& expected, double tolerance,
                      const char* build) {
  const double scale = expected[0].norm() + expected[1].norm() + 1e-300;
  for (size_t a = 0; a < 4; ++a)
    EXPECT_LT(
        (Eigen::Map<const Eigen::Vector3d>(forces.data() + 12 * t + 3 * a) - expected[a]).norm(),
        tolerance * scale)
        << build << " tet " << t;
}

// The batched per-tet pass (F, rotation, forces, energy, four tets at a time) against the element
// functions it replaces, in each build: random deformations, warm-started from a nearby rotation,
// the batch cut short at the end, and inverted tets flagged for the SVD path, not computed.
TEST(SystemOperatorKernels, BatchedTet4ForcePassMatchesTheElementFunctions) {
  auto model = beam(ElementKind::kTet4);
  const int tets = model->elementCount() - 1;  // a short last batch
  const std::vector<double> positions = deformedPositions(*model, kTurn, 0.02, 5);
  std::vector<int> nodes = model->elementNodes();
  std::swap(nodes[4 * 7 + 1], nodes[4 * 7 + 2]);  // tet 7 inverted
  const double mu = model->material().mu(), lambda = model->material().lambda();
  for (const system_kernels::KernelTable* build : kernelBuilds()) {
    const Eigen::Quaterniond start(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX()) *
                                   Eigen::Quaterniond(kTurn));
    std::vector<Eigen::Quaterniond> q(static_cast<size_t>(tets), start);
    std::vector<Eigen::Matrix3d> R(q.size());
    std::vector<double> forces(12 * q.size()), energy(q.size()), strain(q.size());
    std::vector<unsigned char> needs_svd(q.size(), 2);
    system_kernels::Tet4ForceInput in;
    in.positions = positions.data();
    in.nodes = nodes.data();
    in.rest = model->tetRestData().data()->rest_shape_inverse.data();
    in.mu = mu;
    in.lambda = lambda;
    in.quaternions = q.data()->coeffs().data();
    in.rotations = R.data()->data();
    in.forces = forces.data();
    in.energy = energy.data();
    in.volumetric_strain = strain.data();
    in.needs_svd = needs_svd.data();
    build->tet4_forces(in, 0, tets);
    for (size_t t = 0; t < q.size(); ++t) {
      const std::array<Eigen::Vector3d, 4> x = tetCorners(positions, nodes, t);
      const TetRestData& rest = model->tetRestData()[t];
      const Eigen::Matrix3d F = deformationGradient(x, rest.rest_shape_inverse);
      ASSERT_EQ(needs_svd[t], F.determinant() > 0 ? 0 : 1) << t;
      if (needs_svd[t]) continue;
      Eigen::Quaterniond q_ref = start;
      const Eigen::Matrix3d R_ref = extractRotation(F, q_ref);
      EXPECT_LT((R[t] - R_ref).norm(), 1e-12) << build->name << " tet " << t;
      const CorotatedResponse ref = corotatedResponse(F, R_ref, rest, mu, lambda);
      expectForcesNear(forces, t, ref.forces, 1e-9, build->name);
      EXPECT_NEAR(energy[t], ref.energy, 1e-9 * ref.energy) << build->name;
      EXPECT_NEAR(strain[t], (R_ref.transpose() * F).trace() - 3.0, 1e-12) << build->name;
    }
    EXPECT_EQ(needs_svd[7], 1);
  }
}

// The batched stable neo-Hookean pass against the element functions it replaces, in each build:
// energy and forces of hyperelasticTetForces and the factors of factoredTetHessian, on large
// random deformations (stretch, shear and a tet turned inside out: the law is defined there),
// a short last batch, and the tets below a barrier threshold flagged and left alone.
TEST(SystemOperatorKernels, BatchedNeoHookeanPassMatchesTheElementFunctions) {
  auto model = beam(ElementKind::kTet4);
  const int tets = model->elementCount() - 1;  // a short last batch
  Eigen::Matrix3d stretch;
  stretch << 1.6, 0.3, 0, 0, 0.8, 0.2, 0.1, 0, 0.7;
  const std::vector<double> positions = deformedPositions(*model, kTurn * stretch, 0.05, 11);
  std::vector<int> nodes = model->elementNodes();
  std::swap(nodes[4 * 7 + 1], nodes[4 * 7 + 2]);  // tet 7 inside out: J < 0, still the law's
  const StableNeoHookean law = StableNeoHookean::fromYoungPoisson(1e5, 0.45);
  for (const double threshold : {-std::numeric_limits<double>::infinity(), 0.9}) {
    for (const system_kernels::KernelTable* build : kernelBuilds()) {
      const size_t count = static_cast<size_t>(tets);
      std::vector<double> forces(12 * count), energy(count), factors(30 * count);
      std::vector<unsigned char> needs_scalar(count, 2);
      system_kernels::NeoHookeanTet4Input in;
      in.positions = positions.data();
      in.nodes = nodes.data();
      in.rest = model->tetRestData().data()->rest_shape_inverse.data();
      in.mu = law.mu;
      in.lambda = law.lambda;
      in.alpha = law.alpha;
      in.rest_energy = law.rest_energy;
      in.barrier_threshold = threshold;
      in.forces = forces.data();
      in.energy = energy.data();
      in.factors = factors.data();
      in.needs_scalar = needs_scalar.data();
      build->neo_hookean_tet4(in, 0, tets);
      int flagged = 0;
      for (size_t t = 0; t < count; ++t) {
        const std::array<Eigen::Vector3d, 4> x = tetCorners(positions, nodes, t);
        const TetRestData& rest = model->tetRestData()[t];
        const Eigen::Matrix3d F = deformationGradient(x, rest.rest_shape_inverse);
        const double J = F.determinant();
        ASSERT_EQ(needs_scalar[t], J < threshold ? 1 : 0) << build->name << " tet " << t;
        if (needs_scalar[t] != 0) {
          ++flagged;
          continue;
        }
        const HyperelasticTetForces ref = hyperelasticTetForces(law, x, rest);
        expectForcesNear(forces, t, ref.forces, 1e-12, build->name);
        EXPECT_NEAR(energy[t], ref.energy, 1e-12 * std::abs(ref.energy)) << build->name;
        const FactoredTetHessian h =
            factoredTetHessian(F, shapeGradients(rest.rest_shape_inverse), rest.volume, law.lambda,
                               law.lambda * (J - law.alpha));
        const double c_scale = h.c[0].norm() + h.c[1].norm();
        const double w_scale = h.w[0].norm() + h.w[5].norm() + 1e-300;
        for (size_t a = 0; a < 4; ++a)
          EXPECT_LT((Eigen::Map<const Eigen::Vector3d>(&factors[30 * t + 3 * a]) - h.c[a]).norm(),
                    1e-12 * c_scale)
              << build->name << " tet " << t;
        for (size_t p = 0; p < 6; ++p)
          EXPECT_LT(
              (Eigen::Map<const Eigen::Vector3d>(&factors[30 * t + 12 + 3 * p]) - h.w[p]).norm(),
              1e-12 * w_scale)
              << build->name << " tet " << t;
      }
      if (threshold > 0) {
        EXPECT_GT(flagged, 0);  // the inside-out tet at least
        EXPECT_EQ(needs_scalar[7], 1);
      } else {
        EXPECT_EQ(flagged, 0);
      }
    }
  }
}

// The exact Hessian assembled from its factors (the kernel a Newton direction runs) against the
// same Hessians expanded to 12x12 element stiffnesses and assembled block by block, in each
// build: on large random deformations with a tet inside out, and with lagged blocks (a step's
// stiffness damping) added by the assembly at a weight, as both forms take them.
TEST(SystemOperatorKernels, FactoredAssemblyMatchesTheExpandedElementStiffnesses) {
  auto model = beam(ElementKind::kTet4);
  Eigen::Matrix3d stretch;
  stretch << 1.6, 0.3, 0, 0, 0.8, 0.2, 0.1, 0, 0.7;
  const std::vector<double> positions = deformedPositions(*model, kTurn * stretch, 0.05, 13);
  const std::vector<int>& nodes = model->elementNodes();
  const StableNeoHookean law = StableNeoHookean::fromYoungPoisson(1e5, 0.45);
  ElementStiffnesses factored, expanded;
  factored.factored_shear = law.mu;
  for (size_t t = 0; t < static_cast<size_t>(model->elementCount()); ++t) {
    const std::array<Eigen::Vector3d, 4> x = tetCorners(positions, nodes, t);
    const TetRestData& rest = model->tetRestData()[t];
    const Eigen::Matrix3d F = deformationGradient(x, rest.rest_shape_inverse);
    const std::array<Eigen::Vector3d, 4> g = shapeGradients(rest.rest_shape_inverse);
    // Tet 7 mirrored: J < 0 (the law is defined there, and its factors change sign).
    const Eigen::Matrix3d tet_F = t == 7 ? Eigen::Matrix3d(-F) : F;
    factored.factored_tet4.push_back(factoredTetHessian(
        tet_F, g, rest.volume, law.lambda, law.lambda * (tet_F.determinant() - law.alpha)));
    expanded.tet4.push_back(
        expandFactoredHessian(factored.factored_tet4.back(), g, law.mu * rest.volume));
  }
  Parallel parallel(2);
  SystemOperator corotated(model, parallel);
  std::mt19937 rng(17);
  randomRotations(corotated, rng);
  const std::vector<Eigen::Matrix3d> lagged = corotated.stiffnessBlocks();
  for (const double weight : {0.0, 3.5}) {
    SystemOperator reference(model, parallel);
    reference.setElementStiffnesses(&expanded);
    if (weight != 0) reference.setLaggedStiffness(&lagged, weight);
    const std::vector<Eigen::Matrix3d>& want = reference.stiffnessBlocks();
    double largest = 0;
    for (const Eigen::Matrix3d& block : want)
      largest = std::max(largest, block.cwiseAbs().maxCoeff());
    for (const bool baseline : {false, true}) {
      SystemOperator op(model, parallel);
      op.useBaselineKernels(baseline);
      op.setElementStiffnesses(&factored);
      if (weight != 0) op.setLaggedStiffness(&lagged, weight);
      const std::vector<Eigen::Matrix3d>& got = op.stiffnessBlocks();
      ASSERT_EQ(got.size(), want.size());
      double difference = 0;
      for (size_t s = 0; s < got.size(); ++s)
        difference = std::max(difference, (got[s] - want[s]).cwiseAbs().maxCoeff());
      EXPECT_LE(difference, 1e-12 * largest) << op.kernelPath() << " weight " << weight;
    }
  }
}

// A step keeps K_0 for its damping by taking the blocks (no copy): the taken blocks are K, and
// the operator, its storage handed over, assembles the same K again at its next use.
TEST(SystemOperatorKernels, TakenBlocksAreKAndTheOperatorAssemblesAgain) {
  auto model = beam(ElementKind::kTet4);
  Parallel parallel(1);
  SystemOperator op(model, parallel), fresh(model, parallel);
  std::mt19937 rng(19);
  randomRotations(op, rng);
  fresh.mutableRotations() = op.rotations();
  op.setCoefficients(1.01, 1e-4);
  fresh.setCoefficients(1.01, 1e-4);
  std::vector<Eigen::Matrix3d> taken(3, Eigen::Matrix3d::Constant(7.0));  // storage handed back
  op.takeStiffnessBlocks(taken);
  const std::vector<Eigen::Matrix3d>& want = fresh.stiffnessBlocks();
  ASSERT_EQ(taken.size(), want.size());
  EXPECT_EQ(std::memcmp(taken.data(), want.data(), want.size() * sizeof(Eigen::Matrix3d)), 0);
  const Eigen::VectorXd y = randomVector(3 * model->nodeCount(), rng);
  Eigen::VectorXd a, b;
  op.multiply(y, a);
  fresh.multiply(y, b);
  EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(b.size())), 0);
  EXPECT_EQ(
      std::memcmp(op.stiffnessBlocks().data(), want.data(), want.size() * sizeof(Eigen::Matrix3d)),
      0);
}

// The tet4 force pass writes the rotated gradients K is assembled from (one pass over the tets
// instead of two): K must be bit for bit the one the assembly's own pass gives for the same
// rotations, including a tet the force pass hands to the SVD path (inverted).
TEST(SystemOperatorKernels, ForcePassGradientsGiveBitForBitTheAssemblysMatrix) {
  // Without the volume barrier, whose stiffness the stepper adds to K for the inverted tet
  // (tests/unit/volume_barrier_test.cpp checks that part).
  Material material;
  material.barrier_threshold = 0;
  auto model = FemModel::create(beam(ElementKind::kTet4)->linearMeshPtr(), material).value();
  Parallel parallel(2);
  ImplicitStepper stepper(model, SolverSettings{}, parallel);
  FemState state = FemState::atRest(*model);
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0, 0.05);
  for (int i = 0; i < state.positions.size(); ++i)
    state.positions[i] += n(rng);
  // Invert the first tet: its fourth node through the opposite face.
  const int* first = model->elementNodes().data();
  const Eigen::Vector3d centre =
      (state.position(first[0]) + state.position(first[1]) + state.position(first[2])) / 3.0;
  state.positions.segment<3>(3 * first[3]) = 2.0 * centre - state.position(first[3]);
  stepper.computeElasticForces(state);
  const std::vector<Eigen::Matrix3d>& fused = stepper.system().stiffnessBlocks();

  SystemOperator own(model, parallel);
  own.mutableRotations() = stepper.system().rotations();
  const std::vector<Eigen::Matrix3d>& separate = own.stiffnessBlocks();
  ASSERT_EQ(fused.size(), separate.size());
  EXPECT_EQ(std::memcmp(fused.data(), separate.data(), fused.size() * sizeof(Eigen::Matrix3d)), 0);
}

// The reference residual's product from the prescribed nodes alone: bit for bit the full product.
TEST(SystemOperatorKernels, ProductFromAFewNodesIsBitForBitTheFullProduct) {
  auto model = beam(ElementKind::kTet4);
  Parallel parallel(2);
  SystemOperator op(model, parallel);
  std::mt19937 rng(7);
  randomRotations(op, rng);
  op.setCoefficients(1.01, 1e-4);
  const std::vector<int> nodes = {0, 3, model->nodeCount() - 1};
  Eigen::VectorXd y = Eigen::VectorXd::Zero(3 * model->nodeCount());
  for (int node : nodes)
    y.segment<3>(3 * node) = randomVector(3, rng);
  Eigen::VectorXd full, sparse;
  op.multiply(y, full);
  op.multiplyFromNodes(y, nodes, sparse);
  ASSERT_EQ(full.size(), sparse.size());
  EXPECT_GT(full.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(
      std::memcmp(full.data(), sparse.data(), sizeof(double) * static_cast<size_t>(full.size())),
      0);
}

}  // namespace
}  // namespace torsion
