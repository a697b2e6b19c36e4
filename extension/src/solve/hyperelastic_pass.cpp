#include "hyperelastic_pass.h"

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
                                             const TetRestData& rest, bool project) const {
  return kind == MaterialLaw::kMooneyRivlin ? hyperelasticTet(mooney_rivlin, x, rest, project)
                                            : hyperelasticTet(neo_hookean, x, rest, project);
}

double HyperelasticPass::evaluate(const FemModel& model, const Eigen::VectorXd& positions,
                                  const Parallel& parallel, bool stiffness, bool project) {
  const HyperelasticLaw law = HyperelasticLaw::of(model.material());
  const VolumeBarrier barrier = volumeBarrierOf(model.material());
  const std::vector<int>& nodes = model.elementNodes();
  const std::vector<TetRestData>& rest = model.tetRestData();
  const size_t tets = rest.size();
  forces_.resize(4 * tets);
  energy_.resize(tets);
  in_barrier_.assign(tets, 0);
  if (stiffness) stiffness_.resize(tets);
  parallel.forRange(static_cast<int>(tets), kHyperelasticTetGrain, [&](int begin, int end) {
    for (size_t t = static_cast<size_t>(begin); t < static_cast<size_t>(end); ++t) {
      const std::array<Eigen::Vector3d, 4> x = tetPositions(positions, nodes, t);
      // The stiffness (a 9x9 eigen-decomposition) only when asked: forces are the cheap part.
      HyperelasticTetResponse response;
      const Eigen::Matrix3d F = deformationGradient(x, rest[t].rest_shape_inverse);
      if (stiffness) {
        response = law.tet(x, rest[t], project);
      } else {
        const Eigen::Matrix3d P = law.kind == MaterialLaw::kMooneyRivlin
                                      ? firstPiola(law.mooney_rivlin, F)
                                      : firstPiola(law.neo_hookean, F);
        const Eigen::Matrix3d H = -rest[t].volume * P * rest[t].rest_shape_inverse.transpose();
        response.forces = {-(H.col(0) + H.col(1) + H.col(2)), H.col(0), H.col(1), H.col(2)};
        response.energy = rest[t].volume * law.energyDensity(F);
      }
      if (barrier.threshold > 0 && barrier.pressure > 0 && barrier.active(F.determinant())) {
        in_barrier_[t] = 1;
        response.energy += volumeBarrierEnergy(F, rest[t], barrier);
        const std::array<Eigen::Vector3d, 4> f = volumeBarrierForces(F, rest[t], barrier);
        for (size_t a = 0; a < 4; ++a)
          response.forces[a] += f[a];
        if (stiffness) {
          response.stiffness += project ? volumeBarrierStiffness(F, rest[t], barrier)
                                        : volumeBarrierHessian(F, rest[t], barrier);
        }
      }
      std::copy(response.forces.begin(), response.forces.end(),
                forces_.begin() + static_cast<std::ptrdiff_t>(4 * t));
      energy_[t] = response.energy;
      if (stiffness) stiffness_[t] = response.stiffness;
    }
  });
  barrier_tets_ = 0;
  for (unsigned char in : in_barrier_)
    barrier_tets_ += in;
  return sumInOrder(energy_);
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
