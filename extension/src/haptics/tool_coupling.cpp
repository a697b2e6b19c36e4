#include "torsion/haptics/tool_coupling.h"

#include <BulletCollision/BroadphaseCollision/btDispatcher.h>
#include <BulletCollision/NarrowPhaseCollision/btPersistentManifold.h>
#include <BulletDynamics/Dynamics/btDiscreteDynamicsWorld.h>
#include <BulletDynamics/Dynamics/btRigidBody.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "torsion/bt_conversions.h"
#include "torsion/device/passive_stiffness.h"

namespace torsion::haptics {

namespace {

// m: a manifold point this close or closer touches (Bullet keeps points up to its breaking
// threshold, a few millimetres apart).
constexpr double kTouchingDistance = 1e-4;

// `pull` shortened so that `stiffness * pull` stays within `limit`.
Eigen::Vector3d capped(const Eigen::Vector3d& pull, double stiffness, double limit) {
  const double force = stiffness * pull.norm();
  return force > limit ? Eigen::Vector3d(pull * (limit / force)) : pull;
}

Eigen::Quaterniond rotationOf(const btRigidBody& body) {
  return toEigen(body.getWorldTransform().getRotation()).normalized();
}

}  // namespace

Status ToolCouplingSettings::validate() const {
  auto finiteNonNegative = [](double v) { return v >= 0 && std::isfinite(v); };
  if (!(stiffness > 0 && std::isfinite(stiffness)))
    return Error{"stiffness must be a positive number (N/m)"};
  if (!(angular_stiffness > 0 && std::isfinite(angular_stiffness)))
    return Error{"angular_stiffness must be a positive number (N m/rad)"};
  if (!finiteNonNegative(damping_ratio))
    return Error{"damping_ratio must be a non-negative number (1: critical)"};
  if (!(max_force > 0) || !(max_torque > 0))
    return Error{"max_force and max_torque must be positive (N, N m)"};
  if (contact_stiffness_refresh_steps < 0)
    return Error{"contact_stiffness_refresh_steps must be >= 0 (0: rigid contacts only)"};
  if (!(contact_stiffness_tolerance > 0 && contact_stiffness_tolerance < 1))
    return Error{"contact_stiffness_tolerance must be in (0, 1)"};
  return Ok{};
}

Result<std::unique_ptr<ToolCoupling>> ToolCoupling::create(btRigidBody& tool,
                                                           const FemSoftBodySolver& solver,
                                                           const DeviceMapping& mapping,
                                                           const ToolCouplingSettings& settings) {
  if (Status ok = settings.validate(); !ok) return ok.error();
  if (tool.isStaticOrKinematicObject() || !(tool.getInvMass() > 0))
    return Error{"a tool must be a dynamic rigid body (mass > 0)"};
  return std::unique_ptr<ToolCoupling>(new ToolCoupling(tool, solver, mapping, settings));
}

ToolCoupling::ToolCoupling(btRigidBody& tool, const FemSoftBodySolver& solver,
                           const DeviceMapping& mapping, const ToolCouplingSettings& settings)
    : tool_(tool), solver_(solver), mapping_(mapping), settings_(settings), goal_(mapping.anchor) {
  mass_ = 1.0 / toDouble(tool.getInvMass());
  const Eigen::Vector3d inverse = toEigen(tool.getInvInertiaDiagLocal());
  for (int i = 0; i < 3; ++i)
    local_inertia_[i] = inverse[i] > 0 ? 1.0 / inverse[i] : 0.0;
  linear_damping_ = 2 * settings.damping_ratio * std::sqrt(settings.stiffness * mass_);
  angular_damping_ = 2 * settings.damping_ratio *
                     std::sqrt(settings.angular_stiffness * local_inertia_.maxCoeff());
  tool.setActivationState(DISABLE_DEACTIVATION);
  goal_pose_ = mapping.toDevice(goal_);
}

void ToolCoupling::takeGoal(const device::HandCommand& command) {
  command_tick_ = command.tick;
  command_time_ = command.time;
  if (!command.alive) return;  // a dead device's pose is stale: hold the last goal
  if (const std::optional<Frame> mapped = mapping_.toWorldWithinReach(command.pose)) {
    goal_ = *mapped;
    goal_pose_ = command.pose;
  } else {
    ++rejected_poses_;
  }
}

void ToolCoupling::beforeRigidStep(const device::HandCommand& command, const StepContext& ctx) {
  if (command.tick > 0) takeGoal(command);
  const double h = ctx.dt;
  if (!(h > 0)) return;
  // The goal's velocity over this step (zero on the first: the device is where the tool is).
  if (have_previous_goal_) {
    goal_velocity_ = (goal_.origin - previous_goal_.origin) / h;
    goal_angular_velocity_ =
        rotationVector(goal_.rotation * previous_goal_.rotation.conjugate()) / h;
  }
  previous_goal_ = goal_;
  have_previous_goal_ = true;

  const double k = settings_.stiffness, k_r = settings_.angular_stiffness;
  const double b = linear_damping_, b_r = angular_damping_;
  const Eigen::Vector3d x = toEigen(tool_.getCenterOfMassPosition());
  const Eigen::Quaterniond rotation = rotationOf(tool_);
  const Eigen::Vector3d pull = capped(goal_.origin - x, k, settings_.max_force);
  const Eigen::Vector3d twist_pull =
      capped(rotationVector(goal_.rotation * rotation.conjugate()), k_r, settings_.max_torque);
  saved_force_ = toEigen(tool_.getTotalForce());
  saved_torque_ = toEigen(tool_.getTotalTorque());

  const Eigen::Vector3d v = toEigen(tool_.getLinearVelocity());
  const Eigen::Vector3d w = toEigen(tool_.getAngularVelocity());
  const Eigen::Matrix3d r = rotation.toRotationMatrix();
  const Eigen::Matrix3d inertia = r * local_inertia_.asDiagonal() * r.transpose();
  const double c = h * (h * k + b), c_r = h * (h * k_r + b_r);
  const Eigen::Vector3d v_new =
      (mass_ * v + h * (k * pull + b * goal_velocity_ + saved_force_)) / (mass_ + c);
  const Eigen::Vector3d w_new =
      (inertia + c_r * Eigen::Matrix3d::Identity())
          .ldlt()
          .solve(inertia * w +
                 h * (k_r * twist_pull + b_r * goal_angular_velocity_ + saved_torque_));

  // The step sees body and spring as one: their velocity, the spring's share of the mass (an
  // isotropic addition commutes with the rotation, so it adds to the principal moments), no
  // forces left to apply.
  tool_.setLinearVelocity(toBt(v_new));
  tool_.setAngularVelocity(toBt(w_new));
  tool_.clearForces();
  tool_.setMassProps(static_cast<btScalar>(mass_ + c),
                     toBt(Eigen::Vector3d(local_inertia_.array() + c_r)));
  tool_.updateInertiaTensor();
  gravity_ = toEigen(tool_.getGravity());
  lent_ = true;
}

void ToolCoupling::restoreMass() {
  if (!lent_) return;
  tool_.setMassProps(static_cast<btScalar>(mass_), toBt(local_inertia_));
  tool_.updateInertiaTensor();
  tool_.clearForces();
  tool_.applyCentralForce(toBt(saved_force_));
  tool_.applyTorque(toBt(saved_torque_));
  lent_ = false;
}

void ToolCoupling::afterFemStep(const StepContext& /*ctx*/, bool /*ok*/) {
  const bool stepped = lent_;
  restoreMass();
  if (!stepped) return;
  const Eigen::Vector3d x = toEigen(tool_.getCenterOfMassPosition());
  const Eigen::Vector3d pull = capped(goal_.origin - x, settings_.stiffness, settings_.max_force);
  const Eigen::Vector3d twist_pull =
      capped(rotationVector(goal_.rotation * rotationOf(tool_).conjugate()),
             settings_.angular_stiffness, settings_.max_torque);
  coupling_.force = settings_.stiffness * pull +
                    linear_damping_ * (goal_velocity_ - toEigen(tool_.getLinearVelocity()));
  coupling_.torque =
      settings_.angular_stiffness * twist_pull +
      angular_damping_ * (goal_angular_velocity_ - toEigen(tool_.getAngularVelocity()));
  world_wrench_.force = -coupling_.force;
  world_wrench_.torque = -coupling_.torque;
  if (!settings_.feel_weight) world_wrench_.force -= (mass_ + carried_mass_) * gravity_;

  Matrix6d k_c = Matrix6d::Zero();
  k_c.topLeftCorner<3, 3>().diagonal().setConstant(settings_.stiffness);
  k_c.bottomRightCorner<3, 3>().diagonal().setConstant(settings_.angular_stiffness);
  const Matrix6d k_e = rigidContactStiffness() + femContactStiffness();
  world_stiffness_ = -(k_c - k_c * (k_c + k_e).ldlt().solve(k_c));
}

Matrix6d ToolCoupling::femContactStiffness() {
  Matrix6d k_e = Matrix6d::Zero();
  if (settings_.contact_stiffness_refresh_steps <= 0) return k_e;
  const bool due = ++steps_since_refresh_ >= settings_.contact_stiffness_refresh_steps;
  if (due) steps_since_refresh_ = 0;
  const Eigen::Vector3d centre = toEigen(tool_.getCenterOfMassPosition());
  for (const auto& body : solver_.bodies()) {
    const std::optional<ContactPatch> patch = contactPatch(*body, tool_);
    if (!patch) {
      patch_stiffness_.erase(body.get());  // a new touch starts with a fresh solve
      continue;
    }
    auto known = patch_stiffness_.find(body.get());
    if (due || known == patch_stiffness_.end()) {
      const double k_n =
          contact_stiffness_.normalStiffness(*body, *patch, settings_.contact_stiffness_tolerance);
      known = patch_stiffness_.insert_or_assign(body.get(), k_n).first;
    }
    // The body pushes back along -N through the patch's centre.
    Eigen::Matrix<double, 6, 1> j;
    j << patch->normal, (patch->centre - centre).cross(patch->normal);
    k_e += known->second * j * j.transpose();
  }
  return k_e;
}

Matrix6d ToolCoupling::rigidContactStiffness() const {
  Matrix6d k_e = Matrix6d::Zero();
  btDispatcher* dispatcher =
      solver_.world() != nullptr ? solver_.world()->getDispatcher() : nullptr;
  if (dispatcher == nullptr) return k_e;
  const Eigen::Vector3d centre = toEigen(tool_.getCenterOfMassPosition());
  for (int m = 0; m < dispatcher->getNumManifolds(); ++m) {
    const btPersistentManifold* manifold = dispatcher->getManifoldByIndexInternal(m);
    const bool first = manifold->getBody0() == &tool_;
    if (!first && manifold->getBody1() != &tool_) continue;
    for (int p = 0; p < manifold->getNumContacts(); ++p) {
      const btManifoldPoint& point = manifold->getContactPoint(p);
      if (toDouble(point.getDistance()) > kTouchingDistance) continue;
      // Bullet's normal points from body 1 to body 0.
      const Eigen::Vector3d n = toEigen(point.m_normalWorldOnB);
      const Eigen::Vector3d on_tool =
          toEigen(first ? point.getPositionWorldOnA() : point.getPositionWorldOnB());
      Eigen::Matrix<double, 6, 1> j;
      j << n, (on_tool - centre).cross(n);
      k_e += kRigidContactStiffness * j * j.transpose();
    }
  }
  return k_e;
}

device::SimulationWrench ToolCoupling::publish(std::uint64_t step) {
  device::SimulationWrench out;
  out.step = step;
  out.command_tick = command_tick_;
  out.command_time = command_time_;
  out.pose = goal_pose_;
  out.grabbed = true;  // a tool is always held
  out.wrench = mapping_.wrenchToDevice(world_wrench_);
  mapping_.stiffnessToDevice(world_stiffness_, out.stiffness);
  if (settings_.passive_stiffness) device::passiveStiffness(out.stiffness, out.stiffness);
  return out;
}

}  // namespace torsion::haptics
