#include "hyperelastic_pass.h"

#include <algorithm>
#include <cstring>

#include "torsion/fem/corotated_element.h"

namespace torsion {

namespace {
constexpr int kHyperelasticTetGrain = 128;

std::array<Eigen::Vector3d, 4> tetPositions(const Eigen::VectorXd& positions,
                                            const std::vector<int>& nodes, size_t t) {
  std::array<Eigen::Vector3d, 4> x;
  for (size_t a = 0; a < 4; ++a)
    x[a] = positions.segment<3>(3 * nodes[4 * t + a]);
  return x;
}

double sumInOrder(const std::vector<double>& values) {
  double sum = 0;
  for (double v : values)
    sum += v;
  return sum;
}
}  // namespace

HyperelasticLaw HyperelasticLaw::of(const Material& material) {
  HyperelasticLaw law;
  law.kind = material.law;
  if (material.law == MaterialLaw::kMooneyRivlin) {
    law.mooney_rivlin = MooneyRivlin::fromYoungPoisson(
        material.youngs_modulus, material.poisson_ratio, material.mooney_rivlin_c2_fraction);
  } else {
    law.neo_hookean =
        StableNeoHookean::fromYoungPoisson(material.youngs_modulus, material.poisson_ratio);
  }
  return law;
}

double HyperelasticLaw::energyDensity(const Eigen::Matrix3d& F) const {
  return kind == MaterialLaw::kMooneyRivlin ? torsion::energyDensity(mooney_rivlin, F)
                                            : torsion::energyDensity(neo_hookean, F);
}

HyperelasticTetResponse HyperelasticLaw::tet(const std::array<Eigen::Vector3d, 4>& x,
                                             const TetRestData& rest,
                                             TetStiffnessKind stiffness) const {
  return kind == MaterialLaw::kMooneyRivlin ? hyperelasticTet(mooney_rivlin, x, rest, stiffness)
                                            : hyperelasticTet(neo_hookean, x, rest, stiffness);
}

double HyperelasticPass::evaluate(const FemModel& model, const Eigen::VectorXd& positions,
                                  const Parallel& parallel, TetStiffnessKind kind) {
  const HyperelasticLaw law = HyperelasticLaw::of(model.material());
  const VolumeBarrier barrier = volumeBarrierOf(model.material());
  const std::vector<int>& nodes = model.elementNodes();
  const std::vector<TetRestData>& rest = model.tetRestData();
  const size_t tets = rest.size();
  const bool projected =
      kind == TetStiffnessKind::kProjected || kind == TetStiffnessKind::kProjectedAndExact;
  const bool exact =
      kind == TetStiffnessKind::kExact || kind == TetStiffnessKind::kProjectedAndExact;
  forces_.resize(4 * tets);
  energy_.resize(tets);
  in_barrier_.assign(tets, 0);
  if (projected) projected_.resize(tets);
  if (exact) exact_.resize(tets);
  parallel.forRange(static_cast<int>(tets), kHyperelasticTetGrain, [&](int begin, int end) {
    for (size_t t = static_cast<size_t>(begin); t < static_cast<size_t>(end); ++t) {
      const std::array<Eigen::Vector3d, 4> x = tetPositions(positions, nodes, t);
      HyperelasticTetResponse response = law.tet(x, rest[t], kind);
      const Eigen::Matrix3d F = deformationGradient(x, rest[t].rest_shape_inverse);
      if (barrier.threshold > 0 && barrier.pressure > 0 && barrier.active(F.determinant())) {
        in_barrier_[t] = 1;
        response.energy += volumeBarrierEnergy(F, rest[t], barrier);
        const std::array<Eigen::Vector3d, 4> f = volumeBarrierForces(F, rest[t], barrier);
        for (size_t a = 0; a < 4; ++a)
          response.forces[a] += f[a];
        if (projected) response.projected_stiffness += volumeBarrierStiffness(F, rest[t], barrier);
        if (exact) response.exact_stiffness += volumeBarrierHessian(F, rest[t], barrier);
      }
      std::copy(response.forces.begin(), response.forces.end(),
                forces_.begin() + static_cast<std::ptrdiff_t>(4 * t));
      energy_[t] = response.energy;
      if (projected) projected_[t] = response.projected_stiffness;
      if (exact) exact_[t] = response.exact_stiffness;
    }
  });
  barrier_tets_ = 0;
  for (unsigned char in : in_barrier_)
    barrier_tets_ += in;
  evaluated_positions_ = positions;
  evaluated_kind_ = kind;
  evaluated_energy_ = sumInOrder(energy_);
  return evaluated_energy_;
}

bool HyperelasticPass::holdsProjectedAt(const Eigen::VectorXd& positions) const {
  const bool projected = evaluated_kind_ == TetStiffnessKind::kProjected ||
                         evaluated_kind_ == TetStiffnessKind::kProjectedAndExact;
  // The bits, not the values: -0 and 0 (or two NaNs) are not the same start.
  return projected && evaluated_positions_.size() == positions.size() &&
         std::memcmp(positions.data(), evaluated_positions_.data(),
                     sizeof(double) * static_cast<size_t>(positions.size())) == 0;
}

double HyperelasticPass::energy(const FemModel& model, const Eigen::VectorXd& positions,
                                const Parallel& parallel) {
  const HyperelasticLaw law = HyperelasticLaw::of(model.material());
  const VolumeBarrier barrier = volumeBarrierOf(model.material());
  const std::vector<int>& nodes = model.elementNodes();
  const std::vector<TetRestData>& rest = model.tetRestData();
  energy_.resize(rest.size());
  parallel.forRange(static_cast<int>(rest.size()), kHyperelasticTetGrain, [&](int begin, int end) {
    for (size_t t = static_cast<size_t>(begin); t < static_cast<size_t>(end); ++t) {
      const Eigen::Matrix3d F =
          deformationGradient(tetPositions(positions, nodes, t), rest[t].rest_shape_inverse);
      double e = rest[t].volume * law.energyDensity(F);
      if (barrier.threshold > 0 && barrier.pressure > 0 && barrier.active(F.determinant()))
        e += volumeBarrierEnergy(F, rest[t], barrier);
      energy_[t] = e;
    }
  });
  return sumInOrder(energy_);
}

}  // namespace torsion
