#include "torsion/bullet/hand.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

namespace torsion {

double HandSettings::speedLimit(const Material& material) const {
  if (max_drag_strain <= 0) return std::numeric_limits<double>::infinity();
  const double shear_modulus = material.youngs_modulus / (2 * (1 + material.poisson_ratio));
  return max_drag_strain * std::sqrt(shear_modulus / material.density);
}

Status HandSettings::validate() const {
  if (!(std::isfinite(max_drag_strain) && max_drag_strain >= 0))
    return Error{"hand: max_drag_strain = " + std::to_string(max_drag_strain) +
                 ": must be >= 0 (0 turns the speed limit off)"};
  return Ok{};
}

void HandPursuit::advanceTo(double t) {
  if (!(t > time)) return;
  const double dt = t - time;
  time = t;
  const Eigen::Vector3d shift = goal.origin - patch.origin;
  const double angle = patch.rotation.angularDistance(goal.rotation);  // shortest, in [0, pi]
  const double travel = shift.norm() + angle * reach;  // bounds every grabbed node's travel
  const double allowed = max_speed * dt;
  if (travel <= allowed) {  // also when max_speed is infinite
    patch = goal;
    return;
  }
  const double s = allowed / travel;
  patch.origin += s * shift;
  patch.rotation = patch.rotation.slerp(s, goal.rotation).normalized();
}

Hand::Hand(FemBody& body, std::string name, HandSettings settings)
    : body_(&body),
      name_(std::move(name)),
      settings_(settings),
      speed_limit_(settings.speedLimit(body.model().material())),
      pursuit_(std::make_shared<HandPursuit>()) {
  assert(settings.validate().ok());
}

Result<int> Hand::grab(const Frame& frame, double now) {
  // Checked, not normalised: the frame is used as given, bit for bit.
  if (Result<Frame> checked = checkedFrame(frame, label() + ": the frame"); !checked)
    return checked.error();
  release();
  selection_ = selectGrabbedPatch(body_->model().mesh(), body_->state().positions, frame);
  if (selection_.status != HandSelectionStatus::kGrabbed) {
    return Error{label() + ": " + selection_.message};
  }
  // A fresh pursuit per grab: a motion still held by an earlier group never sees this one.
  pursuit_ = std::make_shared<HandPursuit>();
  pursuit_->goal = frame;
  pursuit_->patch = frame;
  pursuit_->time = now;
  pursuit_->max_speed = speed_limit_;
  for (int node : selection_.nodes)
    pursuit_->reach =
        std::max(pursuit_->reach, (body_->state().position(node) - frame.origin).norm());
  group_ = body_->carryNodes(name_, selection_.nodes, followPursuit(pursuit_), now);
  return static_cast<int>(selection_.nodes.size());
}

FrameMotion followPursuit(std::shared_ptr<HandPursuit> pursuit) {
  return [pursuit = std::move(pursuit)](double t) {
    pursuit->advanceTo(t);
    return pursuit->patch;
  };
}

Status Hand::moveTo(const Frame& frame) {
  // Checked, not normalised: the goal is the frame as given, bit for bit.
  if (Result<Frame> checked = checkedFrame(frame, label() + ": the frame"); !checked)
    return checked.error();
  pursuit_->goal = frame;
  return Ok{};
}

std::string Hand::label() const {
  return "hand '" + name_ + "' on body '" + body_->name() + "'";
}

void Hand::release() {
  if (!grabbed()) return;
  body_->releaseGroup(group_);
  group_ = -1;
}

Wrench Hand::wrench() const {
  if (!grabbed()) return Wrench{};
  // Before the body's first step there are no internal forces yet (FemBody::groupWrench would
  // read an empty buffer).
  if (body_->stepper().elasticForces().size() != body_->state().positions.size()) return Wrench{};
  return body_->groupWrench(group_, pursuit_->patch.origin);
}

const std::vector<int>& Hand::grabbedNodes() const {
  static const std::vector<int> kNone;
  if (!grabbed()) return kNone;
  return body_->groups()[static_cast<size_t>(group_)]->nodes();
}

void Hand::updateSpeedLimit() {
  speed_limit_ = settings_.speedLimit(body_->model().material());
  pursuit_->max_speed = speed_limit_;
}

HandCheckpoint Hand::checkpoint() const {
  return HandCheckpoint{pursuit_, *pursuit_, selection_, group_, speed_limit_};
}

void Hand::restore(const HandCheckpoint& checkpoint) {
  pursuit_ = checkpoint.pursuit;
  *pursuit_ = checkpoint.values;
  selection_ = checkpoint.selection;
  group_ = checkpoint.group;
  speed_limit_ = checkpoint.speed_limit;
}

}  // namespace torsion
