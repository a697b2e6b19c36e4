#include "torsion/haptics/device_mapping.h"

namespace torsion::haptics {

namespace {

Eigen::Vector3d fromDevice(const device::Vec3& v) {
  return {v.x, v.y, v.z};
}
device::Vec3 toDevice(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

}  // namespace

Eigen::Vector3d rotationVector(const Eigen::Quaterniond& q) {
  const Eigen::AngleAxisd aa(q.w() < 0 ? Eigen::Quaterniond(-q.coeffs()) : q);
  return aa.angle() * aa.axis();
}

Frame DeviceMapping::toWorld(const device::Pose& pose) const {
  const device::Quat& q = pose.orientation;
  Frame f;
  f.origin = anchor.toWorld(position_scale * fromDevice(pose.position));
  f.rotation = (anchor.rotation * Eigen::Quaterniond(q.w, q.x, q.y, q.z)).normalized();
  return f;
}

std::optional<Frame> DeviceMapping::toWorldWithinReach(const device::Pose& pose) const {
  const Frame mapped = toWorld(pose);
  if (mapped.origin.allFinite() && mapped.origin.cwiseAbs().maxCoeff() <= kMaxReach &&
      mapped.rotation.coeffs().allFinite())
    return mapped;
  return std::nullopt;
}

device::Pose DeviceMapping::toDevice(const Frame& frame) const {
  const Eigen::Quaterniond q = anchor.rotation.conjugate() * frame.rotation;
  return {haptics::toDevice(anchor.toLocal(frame.origin) / position_scale),
          {q.w(), q.x(), q.y(), q.z()}};
}

device::Wrench DeviceMapping::wrenchToDevice(const Wrench& world) const {
  const Eigen::Quaterniond to_device = anchor.rotation.conjugate();
  return {haptics::toDevice(force_scale * (to_device * world.force)),
          haptics::toDevice(torque_scale * (to_device * world.torque))};
}

void DeviceMapping::stiffnessToDevice(const Matrix6d& world, double out[36]) const {
  // W_d = S_w R^T W_world, dpose_world = [s R dp_d; R dtheta_d]: K_d = S_w R^T K R S_p.
  const Eigen::Matrix3d r = anchor.rotation.toRotationMatrix();
  Matrix6d rotate = Matrix6d::Zero();
  rotate.topLeftCorner<3, 3>() = r;
  rotate.bottomRightCorner<3, 3>() = r;
  Eigen::Matrix<double, 6, 1> wrench_scale, pose_scale;
  wrench_scale << Eigen::Vector3d::Constant(force_scale), Eigen::Vector3d::Constant(torque_scale);
  pose_scale << Eigen::Vector3d::Constant(position_scale), Eigen::Vector3d::Ones();
  const Matrix6d k =
      wrench_scale.asDiagonal() * (rotate.transpose() * world * rotate) * pose_scale.asDiagonal();
  for (int row = 0; row < 6; ++row) {
    for (int col = 0; col < 6; ++col)
      out[6 * row + col] = k(row, col);
  }
}

}  // namespace torsion::haptics
