#include "torsion/constraints/hand.h"

#include <utility>

namespace torsion {

Hand::Hand(FemBody& body, std::string name)
    : body_(&body), name_(std::move(name)), target_(std::make_shared<Frame>()) {}

Result<int> Hand::grab(const Frame& frame, double now) {
  release();
  selection_ = selectGrabbedPatch(body_->model().mesh(), body_->state().positions, frame);
  if (selection_.status != HandSelectionStatus::kGrabbed) {
    return Error{"hand '" + name_ + "' on body '" + body_->name() + "': " + selection_.message};
  }
  *target_ = frame;
  std::shared_ptr<const Frame> target = target_;
  group_ = body_->carryNodes(
      name_, selection_.nodes, [target](double) { return *target; }, now);
  return static_cast<int>(selection_.nodes.size());
}

void Hand::moveTo(const Frame& frame) {
  *target_ = frame;
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
  return body_->groupWrench(group_, target_->origin);
}

const std::vector<int>& Hand::grabbedNodes() const {
  static const std::vector<int> kNone;
  if (!grabbed()) return kNone;
  return body_->groups()[static_cast<size_t>(group_)]->nodes();
}

}  // namespace torsion
