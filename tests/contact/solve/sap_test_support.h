#pragma once
// Shared checks and small builders of the SAP tests (docs/contact-sap.md).

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "torsion/contact/solve/sap_problem.h"
#include "torsion/contact/solve/sap_solver.h"
#include "torsion/fem/fem_model.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion::sap::test {

/// A slender bar along x of `cells` cubic cells of 0.05 m, one across (E 10 MPa, 1000 kg/m^3):
/// the coarse space's tests (a rod for aggregateCountFor from 8 cells on).
inline std::shared_ptr<const FemModel> slenderBarModel(int cells) {
  auto mesh = std::make_shared<const TetMesh>(
      makeBoxTetMesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.05 * cells, 0.05, 0.05), cells, 1,
                     1)
          .value());
  Material material;
  material.youngs_modulus = 1e7;
  material.density = 1000;
  return FemModel::create(mesh, material).value();
}

constexpr double kGravity = 9.81;

/// Every row of a solve obeys the lagged model (sap_problem.h): the normal impulse is the
/// compliant law's, gamma_n >= 0 with u_n = v_n - v_hat + R_n gamma_n >= 0 and gamma_n u_n = 0;
/// friction lies in the exact disk |gamma_t| <= r = mu gamma_n^lag (1e-12 relative) and opposes
/// the regularised slip u_t = v_t + R_t gamma_t at maximal dissipation, r |u_t| + gamma_t . u_t = 0
/// (u_t = 0 where stuck inside the disk), to rounding of the velocities involved. Also: the solve
/// converged, its residual within its tolerance.
inline void expectCoulombAndComplementarity(const SapProblem& problem, const SapReport& report) {
  EXPECT_TRUE(report.converged) << report.message;
  EXPECT_LE(report.residual, report.tolerance);
  ASSERT_EQ(static_cast<int>(report.impulses.size()), problem.rowCount());
  for (int i = 0; i < problem.rowCount(); ++i) {
    const auto k = static_cast<size_t>(i);
    const RowModel& m = problem.model(i);
    const Eigen::Vector3d& gamma = report.impulses[k];
    const Eigen::Vector3d& vc = report.contact_velocities[k];
    EXPECT_NEAR(m.radius, m.mu * problem.row(i).lagged_normal_impulse, 1e-15 * m.radius);
    EXPECT_GE(gamma(2), 0.0) << "row " << i;
    EXPECT_LE(gamma.head<2>().norm(), m.radius * (1 + 1e-12)) << "row " << i;
    const Eigen::Vector3d r_gamma(m.rt * gamma(0), m.rt * gamma(1), m.rn * gamma(2));
    const Eigen::Vector3d u = vc - Eigen::Vector3d(0, 0, m.v_hat) + r_gamma;
    const double scale = vc.norm() + std::abs(m.v_hat) + r_gamma.norm();
    EXPECT_GE(u(2), -1e-12 * scale) << "row " << i;
    EXPECT_LE(std::abs(gamma(2) * u(2)), 1e-12 * scale * gamma(2)) << "row " << i;
    const Eigen::Vector2d ut = u.head<2>();
    EXPECT_LE(std::abs(m.radius * ut.norm() + gamma.head<2>().dot(ut)), 1e-12 * scale * m.radius)
        << "row " << i;
  }
}

/// The lagged model's loop (docs/contact-sap.md): each row's lagged normal impulse is the
/// previous step's normal impulse of the same contact, rows[i] of this step being lagged[i]'s;
/// lagged is empty or shorter at the first step (new contacts: 0).
inline void carryLaggedImpulses(const std::vector<double>& lagged, std::vector<ContactRow>& rows) {
  for (size_t i = 0; i < rows.size() && i < lagged.size(); ++i)
    rows[i].lagged_normal_impulse = lagged[i];
}

/// The normal impulses of a solve, for the next step's rows.
inline std::vector<double> normalImpulses(const SapReport& report) {
  std::vector<double> normal;
  for (const Eigen::Vector3d& gamma : report.impulses)
    normal.push_back(gamma(2));
  return normal;
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
