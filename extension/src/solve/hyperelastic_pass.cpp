#include "hyperelastic_pass.h"

#include <algorithm>
#include <cstring>
#include <limits>

#include "system_operator_kernels.h"
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

bool HyperelasticLaw::hasFactoredHessian() const {
  return kind == MaterialLaw::kStableNeoHookean && !neo_hookean.log_term;
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

HyperelasticTetForces HyperelasticLaw::tetForces(const std::array<Eigen::Vector3d, 4>& x,
                                                 const TetRestData& rest) const {
  return kind == MaterialLaw::kMooneyRivlin ? hyperelasticTetForces(mooney_rivlin, x, rest)
                                            : hyperelasticTetForces(neo_hookean, x, rest);
}

HyperelasticTet10Response HyperelasticLaw::tet10(const Tet10Vectors& x,
                                                 const QuadraticRestData& rest,
                                                 TetStiffnessKind stiffness) const {
  return kind == MaterialLaw::kMooneyRivlin ? hyperelasticTet10(mooney_rivlin, x, rest, stiffness)
                                            : hyperelasticTet10(neo_hookean, x, rest, stiffness);
}

namespace {

// The linear tets begin..end-1 four at a time, where the kernel can (stable neo-Hookean, no
// projected stiffness asked): their energies, forces and (if `factored`, the array of all tets'
// factors, is not null) factored Hessians. Returns false if it cannot, else flags in
// `needs_scalar` the tets it leaves to Tet4Elements::respond() (the barrier acts on them).
bool batchNeoHookeanTets(const system_kernels::KernelTable& kernels, const FemModel& model,
                         const HyperelasticLaw& law, const VolumeBarrier& barrier,
                         const Eigen::VectorXd& positions, int begin, int end, bool projected,
                         std::vector<Eigen::Vector3d>& forces, std::vector<double>& energy,
                         FactoredTetHessian* factored, std::vector<unsigned char>& needs_scalar) {
  if (projected || !law.hasFactoredHessian()) return false;
  static_assert(sizeof(FactoredTetHessian) == 30 * sizeof(double), "c_0..c_3, then w");
  static_assert(sizeof(TetRestData) == 10 * sizeof(double), "Bm then V, no padding");
  system_kernels::NeoHookeanTet4Input in;
  in.positions = positions.data();
  in.nodes = model.elementNodes().data();
  in.rest = model.tetRestData().data()->rest_shape_inverse.data();
  in.mu = law.neo_hookean.mu;
  in.lambda = law.neo_hookean.lambda;
  in.alpha = law.neo_hookean.alpha;
  in.rest_energy = law.neo_hookean.rest_energy;
  in.barrier_threshold =
      barrierOn(barrier) ? barrier.threshold : -std::numeric_limits<double>::infinity();
  in.forces = forces.data()->data();
  in.energy = energy.data();
  in.factors = factored != nullptr ? factored->c[0].data() : nullptr;
  in.needs_scalar = needs_scalar.data();
  kernels.neo_hookean_tet4(in, begin, end);
  return true;
}

// Where one element's results go: its energy, forces (N of them), and the stiffnesses asked for
// (null: not asked; `factored` replaces `exact` for a law with that form).
template <class Stiffness>
struct ElementOutputs {
  double& energy;
  Eigen::Vector3d* forces;
  Stiffness* projected;
  Stiffness* exact;
  FactoredTetHessian* factored;
  unsigned char& in_barrier;  // tet4: 1 if below the barrier's threshold; tet10: its sub-tets
};

// What differs between the element kinds: the nodes per element, the chunk a thread takes, the
// law's element function and where the volume barrier acts. respond() writes the element's
// energy, forces and stiffnesses with its barrier added, and how many of its linear tets are
// below the barrier's threshold.
struct Tet4Elements {
  static constexpr size_t kNodes = 4;
  static constexpr int kGrain = kHyperelasticTetGrain;
  using Stiffness = TetStiffness;
  static size_t count(const FemModel& model) { return model.tetRestData().size(); }
  static std::vector<TetStiffness>& of(ElementStiffnesses& s) { return s.tet4; }
  static void respond(const FemModel& model, const HyperelasticLaw& law,
                      const VolumeBarrier& barrier, const Eigen::VectorXd& positions, size_t t,
                      TetStiffnessKind kind, ElementOutputs<TetStiffness> out) {
    const TetRestData& rest = model.tetRestData()[t];
    const std::array<Eigen::Vector3d, 4> x = tetPositions(positions, model.elementNodes(), t);
    // The 12x12 stiffnesses only where asked for (building them costs most of the element).
    const TetStiffnessKind element_kind =
        out.exact != nullptr ? kind
        : out.projected != nullptr
            ? (kind == TetStiffnessKind::kMirrored ? kind : TetStiffnessKind::kProjected)
            : TetStiffnessKind::kNone;
    if (element_kind == TetStiffnessKind::kNone) {
      const HyperelasticTetForces response = law.tetForces(x, rest);
      out.energy = response.energy;
      std::copy(response.forces.begin(), response.forces.end(), out.forces);
    } else {
      const HyperelasticTetResponse response = law.tet(x, rest, element_kind);
      out.energy = response.energy;
      std::copy(response.forces.begin(), response.forces.end(), out.forces);
      if (out.projected != nullptr) *out.projected = response.projected_stiffness;
      if (out.exact != nullptr) *out.exact = response.exact_stiffness;
    }
    const Eigen::Matrix3d F = deformationGradient(x, rest.rest_shape_inverse);
    const double J = F.determinant();
    const bool barrier_acts = barrierOn(barrier) && barrier.active(J);
    if (out.factored != nullptr) {
      const StableNeoHookean& nh = law.neo_hookean;
      double curvature = nh.lambda, pressure = nh.lambda * (J - nh.alpha);
      if (barrier_acts) {
        curvature += barrier.densitySecondDerivative(J);
        pressure += barrier.densityDerivative(J);
      }
      *out.factored = factoredTetHessian(F, shapeGradients(rest.rest_shape_inverse), rest.volume,
                                         curvature, pressure);
    }
    if (!barrier_acts) return;
    out.in_barrier = 1;
    out.energy += volumeBarrierEnergy(F, rest, barrier);
    const std::array<Eigen::Vector3d, 4> f = volumeBarrierForces(F, rest, barrier);
    for (size_t a = 0; a < 4; ++a)
      out.forces[a] += f[a];
    if (out.projected != nullptr) *out.projected += volumeBarrierStiffness(F, rest, barrier);
    if (out.exact != nullptr) *out.exact += volumeBarrierHessian(F, rest, barrier);
  }
};

struct Tet10Elements {
  static constexpr size_t kNodes = 10;
  static constexpr int kGrain = kHyperelasticTet10Grain;
  using Stiffness = Tet10Stiffness;
  static size_t count(const FemModel& model) { return model.quadraticRestData().size(); }
  static std::vector<Tet10Stiffness>& of(ElementStiffnesses& s) { return s.tet10; }
  static void respond(const FemModel& model, const HyperelasticLaw& law,
                      const VolumeBarrier& barrier, const Eigen::VectorXd& positions, size_t e,
                      TetStiffnessKind kind, ElementOutputs<Tet10Stiffness> out) {
    HyperelasticTet10Response response = law.tet10(
        elementPositions(positions, model.elementNodes(), e), model.quadraticRestData()[e], kind);
    if (barrierOn(barrier)) {
      out.in_barrier = static_cast<unsigned char>(addSubTetBarrier(
          model, positions, barrier, e, projectedAsked(kind), exactAsked(kind), response.energy,
          response.forces, &response.projected_stiffness, &response.exact_stiffness));
    }
    out.energy = response.energy;
    std::copy(response.forces.begin(), response.forces.end(), out.forces);
    if (out.projected != nullptr) *out.projected = response.projected_stiffness;
    if (out.exact != nullptr) *out.exact = response.exact_stiffness;
  }
};

}  // namespace

double HyperelasticPass::evaluate(const FemModel& model, const Eigen::VectorXd& positions,
                                  const Parallel& parallel, TetStiffnessKind kind) {
  ++evaluations_;
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
  const bool factored = exact && Elements::kNodes == 4 && law.hasFactoredHessian();
  forces_.resize(Elements::kNodes * elements);
  energy_.resize(elements);
  in_barrier_.assign(elements, 0);
  if (projected) Elements::of(projected_).resize(elements);
  if (exact) {
    Elements::of(exact_).resize(factored ? 0 : elements);
    exact_.factored_tet4.resize(factored ? elements : 0);
    exact_.factored_shear = factored ? law.neo_hookean.mu : 0.0;
  }
  needs_scalar_.resize(elements);
  parallel.forRange(static_cast<int>(elements), Elements::kGrain, [&](int begin, int end) {
    bool batched = false;
    if constexpr (Elements::kNodes == 4) {
      batched = batchNeoHookeanTets(
          system_->kernels(), model, law, barrier, positions, begin, end, projected, forces_,
          energy_, factored ? exact_.factored_tet4.data() : nullptr, needs_scalar_);
    }
    for (size_t e = static_cast<size_t>(begin); e < static_cast<size_t>(end); ++e) {
      if (batched && needs_scalar_[e] == 0) continue;
      Elements::respond(model, law, barrier, positions, e, kind,
                        ElementOutputs<typename Elements::Stiffness>{
                            energy_[e], forces_.data() + Elements::kNodes * e,
                            projected ? &Elements::of(projected_)[e] : nullptr,
                            exact && !factored ? &Elements::of(exact_)[e] : nullptr,
                            factored ? &exact_.factored_tet4[e] : nullptr, in_barrier_[e]});
    }
  });
  barrier_tets_ = 0;
  for (unsigned char in : in_barrier_)
    barrier_tets_ += in;
  if (!holdsForcesAt(positions)) {
    evaluated_positions_ = positions;
    exact_current_ = false;
    projected_current_ = false;
  }
  exact_current_ = exact_current_ || exact;
  projected_current_ = projected_current_ || projected;
  evaluated_energy_ = sumInOrder(energy_);
  return evaluated_energy_;
}

bool HyperelasticPass::holdsForcesAt(const Eigen::VectorXd& positions) const {
  // The bits, not the values: -0 and 0 (or two NaNs) are not the same positions.
  return evaluated_positions_.size() == positions.size() &&
         std::memcmp(positions.data(), evaluated_positions_.data(),
                     sizeof(double) * static_cast<size_t>(positions.size())) == 0;
}

bool HyperelasticPass::holdsExactAt(const Eigen::VectorXd& positions) const {
  return exact_current_ && holdsForcesAt(positions);
}

bool HyperelasticPass::holdsProjectedAt(const Eigen::VectorXd& positions) const {
  return projected_current_ && holdsForcesAt(positions);
}

}  // namespace torsion
