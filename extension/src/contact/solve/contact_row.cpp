#include "torsion/contact/solve/contact_row.h"

#include <Eigen/Geometry>
#include <cmath>

namespace torsion::sap {

Eigen::Matrix3d contactFrame(const Eigen::Vector3d& normal) {
  const Eigen::Vector3d n = normal.normalized();
  // The world axis least aligned with n keeps the cross product well away from zero.
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(n(k)) < std::abs(n(axis))) axis = k;
  const Eigen::Vector3d t1 = n.cross(Eigen::Vector3d::Unit(axis)).normalized();
  const Eigen::Vector3d t2 = n.cross(t1);
  Eigen::Matrix3d frame;
  frame.row(0) = t1.transpose();
  frame.row(1) = t2.transpose();
  frame.row(2) = n.transpose();
  return frame;
}

ContactTerm nodeTerm(int body, int node, double weight, const Eigen::Matrix3d& frame) {
  ContactTerm term;
  term.body = body;
  term.first_dof = 3 * node;
  term.block = weight * frame;
  return term;
}

ContactTerm rigidPointTerm(int body, const Eigen::Vector3d& offset, double sign,
                           const Eigen::Matrix3d& frame) {
  // v_point = v + omega x r = v - [r]x omega.
  Eigen::Matrix3d r_cross;
  r_cross << 0, -offset.z(), offset.y(), offset.z(), 0, -offset.x(), -offset.y(), offset.x(), 0;
  ContactTerm term;
  term.body = body;
  term.first_dof = 0;
  term.block.resize(3, 6);
  term.block.leftCols<3>() = sign * frame;
  term.block.rightCols<3>() = -sign * frame * r_cross;
  return term;
}

}  // namespace torsion::sap
