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
                              bool project) const;
};

class HyperelasticPass {
 public:
  /// Energy, forces (elementForces()) and, with `stiffness`, the element stiffnesses
  /// (elementStiffnesses()) at `positions` (3n): from the projected tangent (positive
  /// semi-definite), or with `project` false the exact Hessians. Returns the energy, J.
  double evaluate(const FemModel& model, const Eigen::VectorXd& positions, const Parallel& parallel,
                  bool stiffness, bool project = true);
  /// The energy alone at `positions`, J (a line search's trial point).
  double energy(const FemModel& model, const Eigen::VectorXd& positions, const Parallel& parallel);

  /// Four per tet, index 4 t + a: the force on the tet's node a, N (SystemOperator::gather).
  const std::vector<Eigen::Vector3d>& elementForces() const { return forces_; }
  /// One per tet: d2E/dx2, N/m (the last evaluate() with stiffness).
  const std::vector<TetStiffness>& elementStiffnesses() const { return stiffness_; }
  /// Keeps the last evaluate()'s stiffnesses as the step's start stiffnesses (a swap, no copy);
  /// the next evaluate() with stiffness writes elsewhere.
  void keepAsStartStiffnesses() { std::swap(stiffness_, start_stiffness_); }
  const std::vector<TetStiffness>& startStiffnesses() const { return start_stiffness_; }
  /// Tets below the volume barrier's threshold at the last evaluate().
  int barrierTets() const { return barrier_tets_; }

 private:
  std::vector<Eigen::Vector3d> forces_;
  std::vector<TetStiffness> stiffness_, start_stiffness_;
  std::vector<double> energy_;
  std::vector<unsigned char> in_barrier_;
  int barrier_tets_ = 0;
};

}  // namespace torsion
