#pragma once
// The simulation side of the haptic coupling for one hand (docs/design.md section 4; the report's
// chapter 5): it turns the loop's HandCommands into Hand::grab / moveTo / release before each
// step, and after the step publishes what the loop renders: the wrench in the device frame, the
// device pose it belongs to and the 6x6 local stiffness K_h.
//
// Rendering:
//   - internal force (default): the wrench the body exerts on the grabbed nodes, F = sum f_l,
//     tau = sum (p_l - O) x f_l, f_l elastic + damping forces, O the patch frame's origin;
//     K_h = PatchStiffness, refreshed every `stiffness_refresh_steps` steps, computed a few
//     columns per step (`stiffness_columns_per_step`). When the patch lags the device (the
//     hand's speed limit), the device feels a virtual coupling (Colgate's) between the two
//     frames on top: W_c = -k (lag) - b d(lag)/dt, k_t = E c_f, k_r = E c_t, b = lag_damping_time
//     k (the damper only while the lag grows), each part's norm at most max_lag_force /
//     max_lag_torque, lag = (goal O - patch O,
//     rotation vector of goal R patch R^-1); then K_h = diag(-k_t, -k_r), since the patch
//     moves at its speed limit whatever the device does. Once the patch has caught up the lag
//     is zero and the rendering is the internal force alone;
//   - frame difference (the report's Algorithm 4): F = -E c_f (O - Center - LocalRestPosition),
//     tau = -E c_t theta(R Orientation^-1 LocalRestOrientation^-1), with Center the grabbed
//     nodes' rest centroid, Orientation the body's rest orientation (identity), the Local* terms
//     captured at grab (BeginInteraction); signs chosen so the feedback opposes the displacement
//     (the report's section 6.2). c_f in m and c_t in m^3 make E c d newtons and E c theta N m;
//     the report's single unitless "damping coefficient" is not dimensionally consistent.
//     K_h = diag(-E c_f, -E c_t): the rendering is linear in the pose, so the local model is exact.
// Buttons (report section 5.4): a new button-1 request grabs at the device's frame (and the loop
// enables force), a new button-2 request releases (force off). Simulation thread only.

#include <cstdint>
#include <limits>
#include <string>

#include "torsion/bullet/hand.h"
#include "torsion/device/device_types.h"
#include "torsion/haptics/device_coupling.h"
#include "torsion/haptics/device_mapping.h"
#include "torsion/haptics/patch_stiffness.h"
#include "torsion/result.h"

namespace torsion::haptics {

enum class Rendering { kInternalForce, kFrameDifference };
const char* toString(Rendering rendering);

struct CouplingSettings {
  Rendering rendering = Rendering::kInternalForce;
  double force_coefficient = 0.1;    ///< c_f, m (frame difference)
  double torque_coefficient = 0.05;  ///< c_t, m^3 (frame difference)
  int stiffness_refresh_steps = 10;  ///< internal force: K_h every this many steps; 0: K_h = 0
  /// K_h columns (one CG solve each) computed per step; 6: the whole refresh in one step. 1
  /// keeps every step about as long as the others (the first K_h after a grab: see
  /// first_stiffness_whole).
  int stiffness_columns_per_step = 1;
  /// After a grab, the first K_h whole in the first step (one longer step), so that the loop
  /// predicts from the first published wrench on instead of holding six steps' wrenches; the
  /// refreshes after it go `stiffness_columns_per_step` columns per step.
  bool first_stiffness_whole = true;
  double stiffness_tolerance = 1e-3;  ///< relative CG tolerance of the K_h solves
  /// Publish only K_h's passive part (symmetric, negative semidefinite in device units;
  /// device/passive_stiffness.h), so the loop's prediction between steps cannot generate energy.
  bool passive_stiffness = true;
  bool lag_coupling = true;        ///< internal force: the virtual coupling across the hand's lag
  double lag_damping_time = 0.05;  ///< s, b / k of the lag coupling's damper
  double max_lag_force = std::numeric_limits<double>::infinity();   ///< N, world
  double max_lag_torque = std::numeric_limits<double>::infinity();  ///< N m, world

  Status validate() const;
};

class HandCoupling : public DeviceCoupling {
 public:
  /// The hand must outlive the coupling. Settings must be valid.
  HandCoupling(Hand& hand, const DeviceMapping& mapping, const CouplingSettings& settings);

  /// Before FemWorld::step(): acts on `command` (grab, release, move). `now` is the world time.
  /// Returns an error when a requested grab found nothing to hold (the hand stays empty).
  /// A pose whose world frame (after the mapping's scale) is not finite or farther than
  /// DeviceMapping::kMaxReach from the origin is dropped and counted: the last goal is held.
  Status apply(const device::HandCommand& command, double now);
  /// DeviceCoupling: apply() at the step's start.
  Status beforeFemStep(const device::HandCommand& command, const StepContext& ctx) override {
    return apply(command, ctx.time);
  }
  /// Poses dropped by apply() because their mapped frame was out of reach or not finite.
  std::uint64_t rejectedPoses() const override { return rejected_poses_; }

  /// After the step: the wrench for the loop, in device units. `step` is the world's step count.
  device::SimulationWrench publish(std::uint64_t step) override;

  /// The rendered wrench of the last publish(), world frame, about the device frame's origin.
  const Wrench& worldWrench() const override { return world_wrench_; }
  /// K_h of the last publish(), world frame.
  const Matrix6d& worldStiffness() const { return world_stiffness_; }
  /// The device's frame in the world (the goal given to the hand).
  const Frame& goal() const { return goal_; }
  /// The lag coupling's part of the last publish()'s wrench (world, zero when not lagging).
  const Wrench& lagWrench() const { return lag_wrench_; }
  Hand& hand() { return hand_; }
  const DeviceMapping& mapping() const { return mapping_; }

 private:
  Wrench frameDifferenceWrench() const;
  /// The virtual coupling across the patch's lag behind the goal at world time `now`; false
  /// (and `out` untouched) when not lagging.
  bool lagCoupling(double now, Wrench& out);

  Hand& hand_;
  DeviceMapping mapping_;
  CouplingSettings settings_;
  std::uint32_t grabs_seen_ = 0, releases_seen_ = 0;
  std::uint64_t command_tick_ = 0;
  double command_time_ = 0;
  device::Pose goal_pose_;
  std::uint64_t rejected_poses_ = 0;
  Frame goal_;
  // BeginInteraction (Algorithm 3)
  Eigen::Vector3d rest_center_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d local_rest_position_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond local_rest_orientation_ = Eigen::Quaterniond::Identity();
  PatchStiffness stiffness_;
  int steps_since_refresh_ = 0;
  bool stiffness_valid_ = false;
  Matrix6d stiffness_cache_ = Matrix6d::Zero();
  Matrix6d world_stiffness_ = Matrix6d::Zero();
  Wrench world_wrench_;
  Wrench lag_wrench_;
  double now_ = 0;  // world time of the last apply()
  Eigen::Matrix<double, 6, 1> previous_lag_ = Eigen::Matrix<double, 6, 1>::Zero();
  double previous_lag_time_ = -1;
};

}  // namespace torsion::haptics
