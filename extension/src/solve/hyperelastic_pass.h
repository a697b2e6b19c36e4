#pragma once
// The element pass of a hyperelastic body (fem/hyperelastic.h), tet4 or tet10: per element its
// energy, forces and element stiffnesses at given node positions, with the volume barrier
// (fem/volume_barrier.h) of the linear tets below its threshold added to the same element (tet4:
// the element itself; tet10: its 8 linear sub-tets, FemModel::mesh(), as for a corotated tet10
// body). Each element writes only its own entries, and sums run in element order, so every
// result is identical for any thread count. Private to the implicit step
// (solve/implicit_stepper.h).

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "torsion/fem/fem_model.h"
#include "torsion/fem/hyperelastic.h"
#include "torsion/fem/volume_barrier.h"
#include "torsion/solve/parallel.h"
#include "torsion/solve/system_operator.h"

namespace torsion {

/// The constants of a body's hyperelastic law (Material::law, E, nu, the C2 fraction).
struct HyperelasticLaw {
  MaterialLaw kind = MaterialLaw::kStableNeoHookean;
  StableNeoHookean neo_hookean;
  MooneyRivlin mooney_rivlin;

  static HyperelasticLaw of(const Material& material);
  /// Whether the exact Hessian of its tet4 has the factored form (fem/factored_tet_hessian.h):
  /// stable neo-Hookean without the log term.
  bool hasFactoredHessian() const;
  double energyDensity(const Eigen::Matrix3d& F) const;
  HyperelasticTetResponse tet(const std::array<Eigen::Vector3d, 4>& x, const TetRestData& rest,
                              TetStiffnessKind kind) const;
  HyperelasticTetForces tetForces(const std::array<Eigen::Vector3d, 4>& x,
                                  const TetRestData& rest) const;
  HyperelasticTet10Response tet10(const Tet10Vectors& x, const QuadraticRestData& rest,
                                  TetStiffnessKind kind) const;
};

class HyperelasticPass {
 public:
  /// The stable neo-Hookean tet4s are computed four at a time by `system`'s kernel build
  /// (SystemOperator::kernels(), read at each evaluate()).
  explicit HyperelasticPass(const SystemOperator& system) : system_(&system) {}

  /// Energy, forces (elementForces()) and the element stiffnesses `kind` asks for
  /// (projectedStiffnesses(): from the clamped, or for kMirrored the mirrored, tangent, positive
  /// semi-definite; exactStiffnesses(): the exact Hessians, factored for a law that has the form,
  /// HyperelasticLaw::hasFactoredHessian) at `positions` (3n). Returns the energy, J. At the
  /// positions of the last evaluate(), the stiffnesses that one computed are kept (a Newton step
  /// asks for the projected ones only where the exact ones fail it).
  double evaluate(const FemModel& model, const Eigen::VectorXd& positions, const Parallel& parallel,
                  TetStiffnessKind kind);
  /// Whether the last evaluate() was at exactly `positions` (the bits: -0 and 0 differ): its
  /// forces and energy are those there (a step that ends there starts the next with them, the same
  /// bits as evaluating again); and whether the exact, or a projected, stiffness is held there.
  bool holdsForcesAt(const Eigen::VectorXd& positions) const;
  bool holdsExactAt(const Eigen::VectorXd& positions) const;
  bool holdsProjectedAt(const Eigen::VectorXd& positions) const;
  /// Forgets the last evaluate() (the material changed).
  void forget() { evaluated_positions_.resize(0); }
  /// The last evaluate()'s energy, J.
  double evaluatedEnergy() const { return evaluated_energy_; }
  /// How many evaluate() calls this pass has made: a caller's copy of the forces is current
  /// while this is unchanged.
  long evaluations() const { return evaluations_; }

  /// N per element (4 for tet4, 10 for tet10), index N e + a: the force on the element's node a,
  /// N (SystemOperator::gather).
  const std::vector<Eigen::Vector3d>& elementForces() const { return forces_; }
  /// One per element in the member of the model's element kind, N/m, at the positions of the
  /// evaluate() that computed them.
  const ElementStiffnesses& projectedStiffnesses() const { return projected_; }
  const ElementStiffnesses& exactStiffnesses() const { return exact_; }
  /// Linear tets below the volume barrier's threshold at the last evaluate() (tet10: sub-tets).
  int barrierTets() const { return barrier_tets_; }

 private:
  /// evaluate() for one element kind (Tet4Elements or Tet10Elements, hyperelastic_pass.cpp).
  template <class Elements>
  double evaluateAs(const FemModel& model, const Eigen::VectorXd& positions,
                    const Parallel& parallel, TetStiffnessKind kind);

  const SystemOperator* system_;
  std::vector<Eigen::Vector3d> forces_;
  ElementStiffnesses projected_, exact_;
  std::vector<double> energy_;
  std::vector<unsigned char> in_barrier_;    // per element: its linear tets below the threshold
  std::vector<unsigned char> needs_scalar_;  // per element: left by the batched kernel
  int barrier_tets_ = 0;
  Eigen::VectorXd evaluated_positions_;
  bool exact_current_ = false;      // exact_ holds the stiffnesses at evaluated_positions_
  bool projected_current_ = false;  // and projected_ the projected ones
  double evaluated_energy_ = 0;
  long evaluations_ = 0;
};

}  // namespace torsion
