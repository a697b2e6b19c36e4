#pragma once
// The element pass of a hyperelastic tet4 body (fem/hyperelastic.h): per tet its energy, forces
// and positive semi-definite stiffness at given node positions, with the volume barrier of the
// tets below its threshold (fem/volume_barrier.h) added to the same tet. Each tet writes only its
// own entries, and sums run in tet order, so every result is identical for any thread count.
// Private to the implicit step (solve/implicit_stepper.h).

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "torsion/fem/fem_model.h"
#include "torsion/fem/hyperelastic.h"
#include "torsion/fem/volume_barrier.h"
#include "torsion/solve/parallel.h"

namespace torsion {

/// The constants of a body's hyperelastic law (Material::law, E, nu, the C2 fraction).
struct HyperelasticLaw {
  MaterialLaw kind = MaterialLaw::kStableNeoHookean;
  StableNeoHookean neo_hookean;
  MooneyRivlin mooney_rivlin;

  static HyperelasticLaw of(const Material& material);
  double energyDensity(const Eigen::Matrix3d& F) const;
  HyperelasticTetResponse tet(const std::array<Eigen::Vector3d, 4>& x, const TetRestData& rest,
                              TetStiffnessKind kind) const;
};

class HyperelasticPass {
 public:
  /// Energy, forces (elementForces()) and the element stiffnesses `kind` asks for
  /// (projectedStiffnesses(): from the projected tangent, positive semi-definite;
  /// exactStiffnesses(): the exact Hessians) at `positions` (3n). Returns the energy, J.
  double evaluate(const FemModel& model, const Eigen::VectorXd& positions, const Parallel& parallel,
                  TetStiffnessKind kind);
  /// The energy alone at `positions`, J (a line search's trial point); the last evaluate()'s
  /// results stay.
  double energy(const FemModel& model, const Eigen::VectorXd& positions, const Parallel& parallel);

  /// Whether the last evaluate() was at exactly `positions` with the projected stiffnesses: a
  /// step that ends there starts the next with them (the same bits as evaluating again).
  bool holdsProjectedAt(const Eigen::VectorXd& positions) const;
  /// Forgets the last evaluate() (the material changed).
  void forget() { evaluated_positions_.resize(0); }
  /// The last evaluate()'s energy, J.
  double evaluatedEnergy() const { return evaluated_energy_; }

  /// Four per tet, index 4 t + a: the force on the tet's node a, N (SystemOperator::gather).
  const std::vector<Eigen::Vector3d>& elementForces() const { return forces_; }
  /// One per tet, N/m (the last evaluate() that computed them).
  const std::vector<TetStiffness>& projectedStiffnesses() const { return projected_; }
  const std::vector<TetStiffness>& exactStiffnesses() const { return exact_; }
  /// Keeps the last evaluate()'s projected stiffnesses as the step's start stiffnesses (a swap,
  /// no copy); the next evaluate() writes elsewhere.
  void keepAsStartStiffnesses() {
    std::swap(projected_, start_stiffness_);
    evaluated_positions_.resize(0);
  }
  const std::vector<TetStiffness>& startStiffnesses() const { return start_stiffness_; }
  /// Tets below the volume barrier's threshold at the last evaluate().
  int barrierTets() const { return barrier_tets_; }

 private:
  std::vector<Eigen::Vector3d> forces_;
  std::vector<TetStiffness> projected_, exact_, start_stiffness_;
  std::vector<double> energy_;
  std::vector<unsigned char> in_barrier_;
  int barrier_tets_ = 0;
  Eigen::VectorXd evaluated_positions_;
  TetStiffnessKind evaluated_kind_ = TetStiffnessKind::kNone;
  double evaluated_energy_ = 0;
};

}  // namespace torsion
