#include "torsion/fem/corotated_element.h"

#include "linear_stress.h"

namespace torsion {

namespace {

// Columns of the 3x3 "force matrix" H = -V P Bm^T are the forces on nodes 1..3; node 0 takes
// minus their sum (the shape gradients sum to zero).
std::array<Eigen::Vector3d, 4> nodeForces(const Eigen::Matrix3d& P, const TetRestData& rest) {
  const Eigen::Matrix3d H = -rest.volume * P * rest.rest_shape_inverse.transpose();
  return {-(H.col(0) + H.col(1) + H.col(2)), H.col(0), H.col(1), H.col(2)};
}

}  // namespace

Eigen::Matrix3d deformationGradient(const std::array<Eigen::Vector3d, 4>& x,
                                    const Eigen::Matrix3d& rest_shape_inverse) {
  Eigen::Matrix3d Ds;
  Ds.col(0) = x[1] - x[0];
  Ds.col(1) = x[2] - x[0];
  Ds.col(2) = x[3] - x[0];
  return Ds * rest_shape_inverse;
}

std::array<Eigen::Vector3d, 4> corotatedForces(const Eigen::Matrix3d& F, const Eigen::Matrix3d& R,
                                               const TetRestData& rest, double mu, double lambda) {
  return corotatedResponse(F, R, rest, mu, lambda).forces;
}

CorotatedResponse corotatedResponse(const Eigen::Matrix3d& F, const Eigen::Matrix3d& R,
                                    const TetRestData& rest, double mu, double lambda) {
  const Eigen::Matrix3d RtF = R.transpose() * F;
  const Eigen::Matrix3d strain = 0.5 * (RtF + RtF.transpose()) - Eigen::Matrix3d::Identity();
  const double trace = strain.trace();
  CorotatedResponse response;
  response.forces = nodeForces(R * detail::linearStress(strain, mu, lambda), rest);
  response.energy = rest.volume * (mu * strain.squaredNorm() + 0.5 * lambda * trace * trace);
  return response;
}

std::array<Eigen::Vector3d, 4> corotatedForceDifferential(const std::array<Eigen::Vector3d, 4>& dx,
                                                          const Eigen::Matrix3d& R,
                                                          const TetRestData& rest, double mu,
                                                          double lambda) {
  const Eigen::Matrix3d dF = deformationGradient(dx, rest.rest_shape_inverse);
  const Eigen::Matrix3d RtdF = R.transpose() * dF;
  const Eigen::Matrix3d dstrain = 0.5 * (RtdF + RtdF.transpose());
  return nodeForces(R * detail::linearStress(dstrain, mu, lambda), rest);
}

double corotatedEnergy(const Eigen::Matrix3d& F, const Eigen::Matrix3d& R, const TetRestData& rest,
                       double mu, double lambda) {
  return corotatedResponse(F, R, rest, mu, lambda).energy;
}

}  // namespace torsion
