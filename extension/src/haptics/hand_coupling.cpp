#include "torsion/haptics/hand_coupling.h"

#include <Eigen/Geometry>
#include <cmath>

#include "torsion/device/passive_stiffness.h"

namespace torsion::haptics {

const char* toString(Rendering rendering) {
  return rendering == Rendering::kInternalForce ? "internal_force" : "frame_difference";
}

Status CouplingSettings::validate() const {
  if (!(force_coefficient >= 0 && std::isfinite(force_coefficient)))
    return Error{"force_coefficient must be a non-negative number (m)"};
  if (!(torque_coefficient >= 0 && std::isfinite(torque_coefficient)))
    return Error{"torque_coefficient must be a non-negative number (m^3)"};
  if (stiffness_refresh_steps < 0) return Error{"stiffness_refresh_steps must be >= 0"};
  if (stiffness_columns_per_step < 1 || stiffness_columns_per_step > 6)
    return Error{"stiffness_columns_per_step must be in [1, 6]"};
  if (!(stiffness_tolerance > 0 && stiffness_tolerance < 1))
    return Error{"stiffness_tolerance must be in (0, 1)"};
  if (!(lag_damping_time >= 0 && std::isfinite(lag_damping_time)))
    return Error{"lag_damping_time must be a non-negative number (s)"};
  if (!(max_lag_force >= 0) || !(max_lag_torque >= 0))
    return Error{"max_lag_force and max_lag_torque must be >= 0"};
  return Ok{};
}

HandCoupling::HandCoupling(Hand& hand, const DeviceMapping& mapping,
                           const CouplingSettings& settings)
    : hand_(hand), mapping_(mapping), settings_(settings), goal_(mapping.anchor) {}

Status HandCoupling::apply(const device::HandCommand& command, double now) {
  command_tick_ = command.tick;
  command_time_ = command.time;
  now_ = now;
  if (command.alive) {  // a dead device's pose is stale: hold the last goal
    if (const std::optional<Frame> mapped = mapping_.toWorldWithinReach(command.pose)) {
      goal_pose_ = command.pose;
      goal_ = *mapped;
    } else {
      ++rejected_poses_;
    }
  }
  // Counters, not edges: several presses between two steps still count once each, in order.
  const bool release = command.release_requests != releases_seen_;
  const bool grab = command.grab_requests != grabs_seen_;
  releases_seen_ = command.release_requests;
  grabs_seen_ = command.grab_requests;
  if (release) hand_.release();
  if (grab && !release) {
    Result<int> grabbed = hand_.grab(goal_, now);
    stiffness_valid_ = false;
    steps_since_refresh_ = 0;
    stiffness_.reset();
    if (!grabbed) return grabbed.error();
    // BeginInteraction: Center and Orientation from the rest state, the hand's offset from them.
    const TetMesh& mesh = hand_.body().model().mesh();
    rest_center_.setZero();
    for (int node : hand_.grabbedNodes())
      rest_center_ += mesh.restPositions()[static_cast<size_t>(node)];
    rest_center_ /= static_cast<double>(hand_.grabbedNodes().size());
    local_rest_position_ = goal_.origin - rest_center_;
    local_rest_orientation_ =
        goal_.rotation;  // HapticOrientation * Orientation^-1, Orientation = I
    return Ok{};
  }
  if (hand_.grabbed()) return hand_.moveTo(goal_);
  return Ok{};
}

Wrench HandCoupling::frameDifferenceWrench() const {
  const double e = hand_.body().model().material().youngs_modulus;
  const Eigen::Vector3d d = goal_.origin - rest_center_ - local_rest_position_;
  const Eigen::Vector3d theta =
      rotationVector(goal_.rotation * local_rest_orientation_.conjugate());
  return {-e * settings_.force_coefficient * d, -e * settings_.torque_coefficient * theta};
}

bool HandCoupling::lagCoupling(double now, Wrench& out) {
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  const Frame& patch = hand_.frame();
  Vector6d lag;
  lag.head<3>() = goal_.origin - patch.origin;
  lag.tail<3>() = rotationVector(goal_.rotation * patch.rotation.conjugate());
  Vector6d rate = Vector6d::Zero();
  if (previous_lag_time_ >= 0 && now > previous_lag_time_)
    rate = (lag - previous_lag_) / (now - previous_lag_time_);
  previous_lag_ = lag;
  previous_lag_time_ = now;
  if (lag.isZero(0)) return false;
  const double e = hand_.body().model().material().youngs_modulus;
  const double k_t = e * settings_.force_coefficient, k_r = e * settings_.torque_coefficient;
  const double b = settings_.lag_damping_time;
  auto bounded = [](const Eigen::Vector3d& v, double limit) {
    const double n = v.norm();
    return n > limit ? Eigen::Vector3d(v * (limit / n)) : v;
  };
  // The damper resists the lag's growth only: while the patch closes in it lets go, so the
  // coupling shrinks with the lag to exactly zero when the patch arrives (a damper that acts
  // part of the time still only takes energy out).
  auto damped = [b](const Eigen::Vector3d& x, const Eigen::Vector3d& v) {
    return x.dot(v) > 0 ? Eigen::Vector3d(x + b * v) : x;
  };
  out.force = bounded(-k_t * damped(lag.head<3>(), rate.head<3>()), settings_.max_lag_force);
  out.torque = bounded(-k_r * damped(lag.tail<3>(), rate.tail<3>()), settings_.max_lag_torque);
  return true;
}

device::SimulationWrench HandCoupling::publish(std::uint64_t step) {
  device::SimulationWrench out;
  out.step = step;
  out.command_tick = command_tick_;
  out.command_time = command_time_;
  out.pose = goal_pose_;
  out.grabbed = hand_.grabbed();
  world_wrench_ = Wrench{};
  lag_wrench_ = Wrench{};
  world_stiffness_.setZero();
  if (!out.grabbed) {
    previous_lag_time_ = -1;
    return out;
  }

  if (settings_.rendering == Rendering::kInternalForce) {
    FemBody& body = hand_.body();
    const bool stepped = body.stepper().elasticForces().size() == body.state().positions.size();
    if (stepped) {
      // About the patch frame's origin: the point the hand holds, the device frame's origin
      // unless the patch lags.
      world_wrench_ = body.groupWrench(hand_.group(), hand_.frame().origin);
      ++steps_since_refresh_;
      const bool due =
          settings_.stiffness_refresh_steps > 0 &&
          (!stiffness_valid_ || steps_since_refresh_ >= settings_.stiffness_refresh_steps);
      if ((due || stiffness_.inProgress()) &&
          stiffness_.advance(body, hand_.group(), goal_.origin, settings_.stiffness_tolerance,
                             !stiffness_valid_ && settings_.first_stiffness_whole
                                 ? 6
                                 : settings_.stiffness_columns_per_step)) {
        stiffness_cache_ = stiffness_.matrix();
        stiffness_valid_ = true;
        steps_since_refresh_ = 0;
      }
      if (stiffness_valid_) world_stiffness_ = stiffness_cache_;
      if (settings_.lag_coupling && lagCoupling(now_, lag_wrench_)) {
        // Colgate's virtual coupling across the lag; while the patch runs at its speed limit
        // the device's motion changes the wrench only through the coupling's spring.
        world_wrench_.force += lag_wrench_.force;
        world_wrench_.torque += lag_wrench_.torque;
        const double e = body.model().material().youngs_modulus;
        world_stiffness_.setZero();
        world_stiffness_.topLeftCorner<3, 3>().diagonal().setConstant(-e *
                                                                      settings_.force_coefficient);
        world_stiffness_.bottomRightCorner<3, 3>().diagonal().setConstant(
            -e * settings_.torque_coefficient);
      }
    }
  } else {
    world_wrench_ = frameDifferenceWrench();
    const double e = hand_.body().model().material().youngs_modulus;
    world_stiffness_.topLeftCorner<3, 3>().diagonal().setConstant(-e * settings_.force_coefficient);
    world_stiffness_.bottomRightCorner<3, 3>().diagonal().setConstant(-e *
                                                                      settings_.torque_coefficient);
  }
  out.wrench = mapping_.wrenchToDevice(world_wrench_);
  mapping_.stiffnessToDevice(world_stiffness_, out.stiffness);
  // In device units (the mapping scales force and torque apart, which can change definiteness):
  // the loop predicts with a restoring, conservative spring only (passive_stiffness.h).
  if (settings_.passive_stiffness) device::passiveStiffness(out.stiffness, out.stiffness);
  return out;
}

}  // namespace torsion::haptics
