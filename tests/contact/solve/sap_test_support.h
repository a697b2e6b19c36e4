#pragma once
// Shared checks and small builders of the SAP tests (docs/contact-solve.md).

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <vector>

#include "torsion/contact/solve/sap_problem.h"
#include "torsion/contact/solve/sap_solver.h"

namespace torsion::sap::test {

constexpr double kGravity = 9.81;

/// Every row of a solve: the impulse lies in Coulomb's cone (exactly: |gamma_t| <= mu gamma_n to
/// 1e-12 relative) and the regularised complementarity holds: with u = v_c - v_hat + R gamma,
/// u lies in the dual cone (mu |u_t| <= u_n) and gamma . u = 0, to rounding of the velocities
/// involved. Also: the solve converged, its residual within its tolerance.
inline void expectCoulombAndComplementarity(const SapProblem& problem, const SapReport& report) {
  EXPECT_TRUE(report.converged) << report.message;
  EXPECT_LE(report.residual, report.tolerance);
  ASSERT_EQ(static_cast<int>(report.impulses.size()), problem.rowCount());
  for (int i = 0; i < problem.rowCount(); ++i) {
    const auto k = static_cast<size_t>(i);
    const RowModel& m = problem.model(i);
    const Eigen::Vector3d& gamma = report.impulses[k];
    const Eigen::Vector3d& vc = report.contact_velocities[k];
    EXPECT_GE(gamma(2), 0.0) << "row " << i;
    EXPECT_LE(gamma.head<2>().norm(), m.mu * gamma(2) * (1 + 1e-12)) << "row " << i;
    const Eigen::Vector3d r_gamma(m.rt * gamma(0), m.rt * gamma(1), m.rn * gamma(2));
    const Eigen::Vector3d u = vc - Eigen::Vector3d(0, 0, m.v_hat) + r_gamma;
    const double scale = vc.norm() + std::abs(m.v_hat) + r_gamma.norm();
    EXPECT_LE(m.mu * u.head<2>().norm() - u(2), 1e-12 * scale) << "row " << i;
    EXPECT_LE(std::abs(gamma.dot(u)), 1e-12 * scale * gamma.norm()) << "row " << i;
  }
}

/// A point mass m (3 dofs) with momentum b = m v0 + dt f.
inline Eigen::SparseMatrix<double> massMatrix(const std::vector<double>& node_masses) {
  const auto n = static_cast<int>(node_masses.size());
  Eigen::SparseMatrix<double> a(3 * n, 3 * n);
  std::vector<Eigen::Triplet<double>> entries;
  for (int i = 0; i < 3 * n; ++i)
    entries.emplace_back(i, i, node_masses[static_cast<size_t>(i / 3)]);
  a.setFromTriplets(entries.begin(), entries.end());
  return a;
}

/// A rigid box's state for the tests' time loops: the centre of mass, orientation, twist
/// [v; omega] (world), half extents and mass.
struct BoxState {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Matrix<double, 6, 1> twist = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Vector3d half = Eigen::Vector3d(0.1, 0.1, 0.05);
  double mass = 1;

  Eigen::Matrix3d rotation() const { return orientation.toRotationMatrix(); }
  /// World inertia about the centre of mass.
  Eigen::Matrix3d inertia() const {
    const Eigen::Vector3d e = 2 * half;
    const Eigen::Vector3d body(e.y() * e.y() + e.z() * e.z(), e.x() * e.x() + e.z() * e.z(),
                               e.x() * e.x() + e.y() * e.y());
    const Eigen::Matrix3d r = rotation();
    return r * (mass / 12 * body).asDiagonal() * r.transpose();
  }
  /// b = M twist + dt (m g, 0) (no gyroscopic term: the boxes barely turn).
  Eigen::VectorXd momentum(const Eigen::Vector3d& gravity, double dt) const {
    Eigen::VectorXd b(6);
    b.head<3>() = mass * (twist.head<3>() + dt * gravity);
    b.tail<3>() = inertia() * twist.tail<3>();
    return b;
  }
  /// Symplectic Euler with the new twist: x += dt v, q = exp(omega dt) q.
  void advance(const Eigen::VectorXd& new_twist, double dt) {
    twist = new_twist;
    position += dt * twist.head<3>();
    const Eigen::Vector3d w = twist.tail<3>() * dt;
    if (w.norm() > 0)
      orientation = Eigen::Quaterniond(Eigen::AngleAxisd(w.norm(), w.normalized())) * orientation;
    orientation.normalize();
  }
  /// The four corners of the bottom face (body z = -half z), world.
  std::vector<Eigen::Vector3d> bottomCorners() const {
    std::vector<Eigen::Vector3d> corners;
    for (int sx : {-1, 1})
      for (int sy : {-1, 1})
        corners.push_back(position +
                          rotation() * Eigen::Vector3d(sx * half.x(), sy * half.y(), -half.z()));
    return corners;
  }
};

}  // namespace torsion::sap::test
