#pragma once
// A rigid frame (origin O, rotation R = [i j k]): the pose of a hand, of a scripted node group,
// of a body. Maps local coordinates p_hat to world p = R p_hat + O (the report's eq. 4.4).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <functional>

namespace torsion {

struct Frame {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();

  Eigen::Vector3d toWorld(const Eigen::Vector3d& local) const { return rotation * local + origin; }
  /// p_hat = R^T (p - O), the report's eq. 4.5.
  Eigen::Vector3d toLocal(const Eigen::Vector3d& world) const {
    return rotation.conjugate() * (world - origin);
  }
};

/// A frame as a function of simulated time (s). Called once per step with that step's end time,
/// in non-decreasing order; a motion may keep state between calls (the hand's pursuit does).
using FrameMotion = std::function<Frame(double time)>;

}  // namespace torsion
