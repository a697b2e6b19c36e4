#include "hyperelastic_pass.h"

#include <algorithm>
#include <cstring>

#include "torsion/fem/corotated_element.h"

namespace torsion {

namespace {
constexpr int kHyperelasticTetGrain = 128;
constexpr int kHyperelasticTet10Grain = 32;

std::array<Eigen::Vector3d, 4> tetPositions(const Eigen::VectorXd& positions,
                                            const std::vector<int>& nodes, size_t t) {
  std::array<Eigen::Vector3d, 4> x;
  for (size_t a = 0; a < 4; ++a)
    x[a] = positions.segment<3>(3 * nodes[4 * t + a]);
  return x;
}

std::array<Eigen::Vector3d, 4> tetPositions(const Eigen::VectorXd& positions, const Tet& tet) {
  std::array<Eigen::Vector3d, 4> x;
  for (size_t a = 0; a < 4; ++a)
    x[a] = positions.segment<3>(3 * tet[a]);
  return x;
}

double sumInOrder(const std::vector<double>& values) {
  double sum = 0;
  for (double v : values)
    sum += v;
  return sum;
}

Tet10Vectors elementPositions(const Eigen::VectorXd& positions, const std::vector<int>& nodes,
                              size_t e) {
  Tet10Vectors x;
  for (size_t a = 0; a < 10; ++a)
    x[a] = positions.segment<3>(3 * nodes[10 * e + a]);
  return x;
}

bool barrierOn(const VolumeBarrier& barrier) {
  return barrier.threshold > 0 && barrier.pressure > 0;
}

// The volume barrier of a tet10 element's 8 linear sub-tets (tets 8 e .. 8 e + 7 of mesh()),
// added to the element's energy, forces and stiffnesses (sub-tet nodes mapped to the element's
// local nodes). Returns how many sub-tets are below the threshold.
int addSubTetBarrier(const FemModel& model, const Eigen::VectorXd& positions,
                     const VolumeBarrier& barrier, size_t e, bool projected, bool exact,
                     double& energy, Tet10Vectors& forces, Tet10Stiffness* projected_stiffness,
                     Tet10Stiffness* exact_stiffness) {
  const std::vector<int>& nodes = model.elementNodes();
  const std::vector<Tet>& tets = model.mesh().tets();
  const std::vector<TetRestData>& rest = model.tetRestData();
  int active = 0;
  for (size_t s = 8 * e; s < 8 * e + 8; ++s) {
    const std::array<Eigen::Vector3d, 4> x = tetPositions(positions, model.mesh().tets()[s]);
    const Eigen::Matrix3d F = deformationGradient(x, rest[s].rest_shape_inverse);
    if (!barrier.active(F.determinant())) continue;
    ++active;
    std::array<size_t, 4> local{};
    for (size_t a = 0; a < 4; ++a)
      for (size_t b = 0; b < 10; ++b)
        if (nodes[10 * e + b] == tets[s][a]) local[a] = b;
    energy += volumeBarrierEnergy(F, rest[s], barrier);
    const std::array<Eigen::Vector3d, 4> f = volumeBarrierForces(F, rest[s], barrier);
    for (size_t a = 0; a < 4; ++a)
      forces[local[a]] += f[a];
    auto add = [&](const TetStiffness& K, Tet10Stiffness& target) {
      for (size_t a = 0; a < 4; ++a)
        for (size_t b = 0; b < 4; ++b)
          target.block<3, 3>(3 * static_cast<int>(local[a]), 3 * static_cast<int>(local[b])) +=
              K.block<3, 3>(3 * static_cast<int>(a), 3 * static_cast<int>(b));
    };
    if (projected) add(volumeBarrierStiffness(F, rest[s], barrier), *projected_stiffness);
    if (exact) add(volumeBarrierHessian(F, rest[s], barrier), *exact_stiffness);
  }
  return active;
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

HyperelasticTet10Response HyperelasticLaw::tet10(const Tet10Vectors& x,
                                                 const QuadraticRestData& rest,
                                                 TetStiffnessKind stiffness) const {
  return kind == MaterialLaw::kMooneyRivlin ? hyperelasticTet10(mooney_rivlin, x, rest, stiffness)
                                            : hyperelasticTet10(neo_hookean, x, rest, stiffness);
}

namespace {

// What differs between the element kinds: the nodes per element, the chunk a thread takes, the
// law's element function and where the volume barrier acts. respond() returns the element's
// energy, forces and stiffnesses with its barrier added, and sets how many of its linear tets are
// below the barrier's threshold.
struct Tet4Elements {
  static constexpr size_t kNodes = 4;
  static constexpr int kGrain = kHyperelasticTetGrain;
  using Response = HyperelasticTetResponse;
  static size_t count(const FemModel& model) { return model.tetRestData().size(); }
  static std::vector<TetStiffness>& of(ElementStiffnesses& s) { return s.tet4; }
  static Response respond(const FemModel& model, const HyperelasticLaw& law,
                          const VolumeBarrier& barrier, const Eigen::VectorXd& positions, size_t t,
                          TetStiffnessKind kind, unsigned char& in_barrier) {
    const TetRestData& rest = model.tetRestData()[t];
    const std::array<Eigen::Vector3d, 4> x = tetPositions(positions, model.elementNodes(), t);
    Response response = law.tet(x, rest, kind);
    const Eigen::Matrix3d F = deformationGradient(x, rest.rest_shape_inverse);
    if (!barrierOn(barrier) || !barrier.active(F.determinant())) return response;
    in_barrier = 1;
    response.energy += volumeBarrierEnergy(F, rest, barrier);
    const std::array<Eigen::Vector3d, 4> f = volumeBarrierForces(F, rest, barrier);
    for (size_t a = 0; a < 4; ++a)
      response.forces[a] += f[a];
    if (projectedAsked(kind))
      response.projected_stiffness += volumeBarrierStiffness(F, rest, barrier);
    if (exactAsked(kind)) response.exact_stiffness += volumeBarrierHessian(F, rest, barrier);
    return response;
  }
};

struct Tet10Elements {
  static constexpr size_t kNodes = 10;
  static constexpr int kGrain = kHyperelasticTet10Grain;
  using Response = HyperelasticTet10Response;
  static size_t count(const FemModel& model) { return model.quadraticRestData().size(); }
  static std::vector<Tet10Stiffness>& of(ElementStiffnesses& s) { return s.tet10; }
  static Response respond(const FemModel& model, const HyperelasticLaw& law,
                          const VolumeBarrier& barrier, const Eigen::VectorXd& positions, size_t e,
                          TetStiffnessKind kind, unsigned char& in_barrier) {
    Response response = law.tet10(elementPositions(positions, model.elementNodes(), e),
                                  model.quadraticRestData()[e], kind);
    if (barrierOn(barrier)) {
      in_barrier = static_cast<unsigned char>(addSubTetBarrier(
          model, positions, barrier, e, projectedAsked(kind), exactAsked(kind), response.energy,
          response.forces, &response.projected_stiffness, &response.exact_stiffness));
    }
    return response;
  }
};

}  // namespace

double HyperelasticPass::evaluate(const FemModel& model, const Eigen::VectorXd& positions,
                                  const Parallel& parallel, TetStiffnessKind kind) {
  return model.elementKind() == ElementKind::kTet10
             ? evaluateAs<Tet10Elements>(model, positions, parallel, kind)
             : evaluateAs<Tet4Elements>(model, positions, parallel, kind);
}

template <class Elements>
double HyperelasticPass::evaluateAs(const FemModel& model, const Eigen::VectorXd& positions,
                                    const Parallel& parallel, TetStiffnessKind kind) {
  const HyperelasticLaw law = HyperelasticLaw::of(model.material());
  const VolumeBarrier barrier = volumeBarrierOf(model.material());
  const size_t elements = Elements::count(model);
  const bool projected = projectedAsked(kind), exact = exactAsked(kind);
  forces_.resize(Elements::kNodes * elements);
  energy_.resize(elements);
  in_barrier_.assign(elements, 0);
  if (projected) Elements::of(projected_).resize(elements);
  if (exact) Elements::of(exact_).resize(elements);
  parallel.forRange(static_cast<int>(elements), Elements::kGrain, [&](int begin, int end) {
    for (size_t e = static_cast<size_t>(begin); e < static_cast<size_t>(end); ++e) {
      typename Elements::Response response =
          Elements::respond(model, law, barrier, positions, e, kind, in_barrier_[e]);
      std::copy(response.forces.begin(), response.forces.end(),
                forces_.begin() + static_cast<std::ptrdiff_t>(Elements::kNodes * e));
      energy_[e] = response.energy;
      if (projected) Elements::of(projected_)[e] = response.projected_stiffness;
      if (exact) Elements::of(exact_)[e] = response.exact_stiffness;
    }
  });
  barrier_tets_ = 0;
  for (unsigned char in : in_barrier_)
    barrier_tets_ += in;
  evaluated_positions_ = positions;
  evaluated_kind_ = kind;
  projected_kept_ = false;
  evaluated_energy_ = sumInOrder(energy_);
  return evaluated_energy_;
}

bool HyperelasticPass::holdsForcesAt(const Eigen::VectorXd& positions) const {
  // The bits, not the values: -0 and 0 (or two NaNs) are not the same positions.
  return evaluated_positions_.size() == positions.size() &&
         std::memcmp(positions.data(), evaluated_positions_.data(),
                     sizeof(double) * static_cast<size_t>(positions.size())) == 0;
}

bool HyperelasticPass::holdsStiffnessesAt(const Eigen::VectorXd& positions) const {
  return (evaluated_kind_ == TetStiffnessKind::kProjectedAndExact ||
          evaluated_kind_ == TetStiffnessKind::kMirroredAndExact) &&
         holdsForcesAt(positions);
}

}  // namespace torsion
