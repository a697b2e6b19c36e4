#pragma once
// A rigid frame (origin O, rotation R = [i j k]): the pose of a hand, of a scripted node group,
// of a body. Maps local coordinates p_hat to world p = R p_hat + O (the report's eq. 4.4).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <functional>
#include <string>

#include "torsion/result.h"

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

/// `frame` as a pose: a finite origin and a unit quaternion up to round-off (1e-6 covers
/// quaternions composed in float or double), returned normalised. Beyond that the rotation was
/// never one (the zero quaternion of `Frame{origin, {}}`), and normalising it would place things
/// where nobody meant: an Error saying which, its message starting with `what` ("the pose").
Result<Frame> checkedFrame(const Frame& frame, const std::string& what);

/// A frame as a function of simulated time (s). Called once per step with that step's end time,
/// in non-decreasing order; a motion may keep state between calls (the hand's pursuit does).
using FrameMotion = std::function<Frame(double time)>;

}  // namespace torsion
