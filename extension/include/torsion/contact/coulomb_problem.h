#pragma once
// Frictional contact in contact space (docs/contact.md, "Coulomb's law solved in contact space"):
// m contacts, contact i with unit normal n_i, Coulomb coefficient mu_i and impulse r_i (a world
// 3-vector, N s, on the soft side). The step's linear system has been condensed onto the contacts:
// their relative velocities (soft side minus rigid side, m/s, the normal part biased by gap / dt so
// that u_n >= 0 means the gap stays open at the step's end) are
//
//     u = u_free + W r,
//
// W the Delassus operator (3m x 3m, symmetric positive semi-definite: the contacts' compliance).
// Coulomb's law, per contact, with r_n = n . r, r_t = r - n r_n, u_n, u_t likewise:
//
//     separate   r = 0 and u_n >= 0
//     stick      u = 0 and |r_t| <= mu r_n
//     slide      u_n = 0, |r_t| = mu r_n, r_t = -mu r_n u_t / |u_t|   (friction against the slip)
//
// A bilateral contact (an anchor) has u = 0 with r unbounded.
//
// Solved by projected Gauss-Seidel: per contact, the normal impulse by its exact 1x1 step projected
// on r_n >= 0, then the friction by a step alpha (the inverse of the tangential block's largest
// eigenvalue) projected on the disc |r_t| <= mu r_n. A fixed point of that iteration is exactly
// Coulomb's law above (the scalar step makes the friction oppose the slip itself, not the slip
// seen through W). Sweeps alone converge slowly where W is ill-conditioned (a box on a stiff slab:
// the box's rank-6 response plus a small compliance), so after a few sweeps the solve takes
// generalised Newton steps on Alart and Curnier's function (Alart & Curnier 1991), a dense
// 3m x 3m solve each, with a backtracking line search; sweeps take over where a step fails.
// Convergence is measured by the natural residual in velocity units (m/s),
// zero exactly at a solution, so a converged answer is a consistent set of stick, slide and
// separate states, whatever W's conditioning.

#include <Eigen/Core>
#include <vector>

namespace torsion {

struct CoulombProblem {
  Eigen::MatrixXd delassus;             ///< W, 3m x 3m, world blocks
  Eigen::VectorXd free_velocity;        ///< u_free, 3m, gap bias included
  std::vector<Eigen::Vector3d> normal;  ///< n_i, unit
  std::vector<double> friction;         ///< mu_i >= 0
  std::vector<char> bilateral;          ///< 1: an anchor (u = 0, r free); empty = none
  int size() const { return static_cast<int>(normal.size()); }
};

struct CoulombSettings {
  /// m/s: the sweeps and Newton steps go on until every contact's natural residual is below this.
  double tolerance = 1e-7;
  int max_sweeps = 2000;
  /// Generalised Newton steps on Alart and Curnier's function (a dense 3m x 3m solve each) after
  /// this many sweeps, for problems of at most newton_max_contacts contacts.
  int sweeps_before_newton = 5;
  int max_newton_steps = 50;
  int newton_max_contacts = 60;
  /// The Newton steps' Jacobian uses W plus this times W's largest diagonal entry: W is only
  /// semi-definite where contacts constrain the same motion (coulomb_problem.cpp). 0 for a
  /// problem whose W is definite (the FEM-rigid solve adds a contact compliance itself).
  double newton_regularization = 1e-6;
  /// m/s: at max_sweeps, a result whose residual is below this still counts as converged (0: only
  /// the tolerance counts). The FEM-rigid contact solve accepts 1e-6 m/s: the slips of a body
  /// resting on a stiff slab are resolved to 1e-7 m/s only in thousands of sweeps.
  double acceptable = 0;
};

struct CoulombReport {
  int sweeps = 0;
  int newton_steps = 0;
  double residual = 0;  ///< m/s, the largest contact's natural residual at the end
  bool converged = false;
};

/// Solves `problem` for the impulses `r` (3m; its content on entry is the warm start, resized and
/// zeroed if its size is wrong). `velocity` returns u = u_free + W r.
CoulombReport solveCoulomb(const CoulombProblem& problem, const CoulombSettings& settings,
                           Eigen::VectorXd& r, Eigen::VectorXd& velocity);

/// The natural residual (m/s) of contact i at impulse r_i and velocity u_i: the distance of r_i
/// from its projection onto the cone after a step of De Saxce's modified velocity
/// u + mu |u_t| n, scaled back to velocity by `step` (kg^-1... 1 / step is an impulse per
/// velocity). Zero exactly when (r_i, u_i) satisfy Coulomb's law.
double coulombResidual(const Eigen::Vector3d& n, double mu, const Eigen::Vector3d& r,
                       const Eigen::Vector3d& u, double step);

/// The projection of r onto the cone {|r_t| <= mu r_n} around unit normal n.
Eigen::Vector3d projectOntoCone(const Eigen::Vector3d& n, double mu, const Eigen::Vector3d& r);

}  // namespace torsion
