#pragma once
// A hand acting on one FEM body through the hand plane (docs/design.md section 3; the report's
// Algorithms 1 and 2).
//
//   Hand hand(*body);
//   Result<int> n = hand.grab(device_frame, world.time());   // Initialize(O, R)
//   while (...) {
//     hand.moveTo(next_device_frame);   // where the device wants the patch
//     world.step();                     // Update: nodes land on R p_hat + O of the patch frame
//     Wrench w = hand.wrench();         // what the body pushes back with, about the patch's O
//   }
//   hand.release();
//
// grab() selects the patch (selectGrabbedPatch) at the body's current positions and hands its
// nodes to FemBody::carryNodes with a FrameMotion that yields the hand's *patch frame*; the body's
// CarriedNodes prescribe them, each step from t to t + dt, to R p_hat + O of that frame in
// position and velocity (the implicit solve sees it; positions are never snapped afterwards).
//
// The patch frame pursues the device frame (the goal, set by moveTo) under a speed limit: it
// reaches the goal at the end of the next step unless that would move some grabbed node faster
// than `HandSettings::speedLimit`, and then gets there over as many steps as it takes. Why: a
// surface patch dragged faster than the material's shear waves can carry the motion inward
// over-deforms the tets between grabbed and free nodes, turning some inside out (the report's
// complaint; docs/hand-plane.md measures it). That is physics, not a solver fault: smaller time
// steps make it worse, not better. The bound is a fraction of the shear wave speed
// c_s = sqrt(G / rho), since a boundary moving at speed v drives a strain of about v / c_s.
// The lag between goal and patch is what a haptic coupling renders as a spring.
//
// Simulation thread only, like the body. The body must outlive the hand's calls. Destroying a
// grabbing hand does not touch the body: its nodes stay held by the pursuit state (the motion owns
// a shared copy of it); call release() first to let go.

#include <memory>
#include <string>
#include <vector>

#include "torsion/bullet/fem_body.h"
#include "torsion/constraints/carried_nodes.h"
#include "torsion/constraints/frame.h"
#include "torsion/constraints/hand_plane.h"
#include "torsion/result.h"

namespace torsion {

struct HandSettings {
  /// The grabbed nodes move at most this fraction of the body's shear wave speed
  /// sqrt(G / rho), i.e. a drag induces a strain of about this much; 0 turns the limit off (the
  /// patch lands on every goal after one step, however fast).
  double max_drag_strain = 0.2;

  /// The speed limit of grabbed nodes for `material`, m/s (infinity when the limit is off).
  double speedLimit(const Material& material) const;
  Status validate() const;
};

/// Where the patch is carried and where the device wants it. Shared by the Hand and the motion it
/// gives the body, so the pursuit goes on if the Hand object is destroyed while grabbing.
struct HandPursuit {
  Frame goal;            ///< the device's frame (last moveTo)
  Frame patch;           ///< the frame carrying the grabbed nodes, at `time`
  double time = 0;       ///< s, world time of `patch`
  double max_speed = 0;  ///< m/s, bound on any grabbed node's speed; infinity: no limit
  double reach = 0;      ///< m, largest |p_hat| of a grabbed node (rotation moves it fastest)

  /// Advances `patch` toward `goal` to time `t` (no-op when t <= time): all the way when the
  /// fastest grabbed node stays under max_speed, else a fraction s of the way (translation lerp,
  /// rotation slerp) with |dO| + angle * reach = max_speed (t - time).
  void advanceTo(double t);
};

/// The motion of a grabbed patch: the pursuit advanced to each time asked, its patch frame.
FrameMotion followPursuit(std::shared_ptr<HandPursuit> pursuit);

/// A hand's state at a moment (Hand::checkpoint), to go back to with the body's checkpoint.
struct HandCheckpoint {
  std::shared_ptr<HandPursuit> pursuit;  ///< the pursuit the body's node group follows then
  HandPursuit values;                    ///< its values then
  HandSelection selection;
  int group = -1;
  double speed_limit = 0;
};

class Hand {
 public:
  /// A hand acting on `body`; `name` names its node groups in the body ("hand" by default).
  /// Settings must be valid (HandSettings::validate); the scene parser checks them for users.
  explicit Hand(FemBody& body, std::string name = "hand", HandSettings settings = {});
  Hand(const Hand&) = delete;  // one hand, one node group: hold it by pointer to share it
  Hand& operator=(const Hand&) = delete;

  /// Initialize(O, R): selects the patch at the body's current positions, stores
  /// p_hat = R^T (p - O) for each of its nodes and starts carrying them by this hand's frame,
  /// which becomes `frame`. Returns the number of grabbed nodes, or an Error with the selection's
  /// message (the plane misses the body, or the ray from O along i misses every cut triangle);
  /// then nothing is grabbed. A hand that already holds a patch releases it first. `now` is the
  /// world's time (FemWorld::time()). A frame that is not a pose (checkedFrame) is an Error too.
  Result<int> grab(const Frame& frame, double now);

  /// Update(O, R): the device's frame, the goal the patch frame pursues from the next step on
  /// (reached at the end of that step unless the speed limit holds it back). Harmless when not
  /// grabbing. Errors (the goal kept): a frame whose origin is not finite or whose rotation is
  /// not a unit quaternion (checkedFrame).
  Status moveTo(const Frame& frame);

  /// Lets go: the grabbed nodes are free from the next step on (FemBody::releaseGroup). The hand
  /// may grab again, elsewhere. No-op when not grabbing.
  void release();

  bool grabbed() const { return group_ >= 0; }

  /// The force and torque (about the patch frame's origin O) that the body exerted on the grabbed
  /// nodes at the end of the last step; zero when not grabbing or before the body's first step.
  Wrench wrench() const;

  /// The grabbed nodes, ascending; empty when not grabbing.
  const std::vector<int>& grabbedNodes() const;
  /// The selection of the last grab() (also when it failed).
  const HandSelection& selection() const { return selection_; }
  /// The goal: the last frame given to grab() or moveTo().
  const Frame& goal() const { return pursuit_->goal; }
  /// The frame the grabbed nodes were carried to in the last step (the goal when not lagging).
  const Frame& frame() const { return pursuit_->patch; }
  /// Speed limit of the grabbed nodes, m/s (infinity when off).
  double speedLimit() const { return speed_limit_; }
  /// Re-derives the speed limit from the body's material after a live edit
  /// (FemBody::setMaterial): a held patch obeys the new limit from the next step on.
  void updateSpeedLimit();
  /// The hand's state, to restore together with its body's FemBody::checkpoint() of the same
  /// moment (the body's node groups hold the hand's patch motion).
  HandCheckpoint checkpoint() const;
  void restore(const HandCheckpoint& checkpoint);

  /// The body's node group carrying the patch, or -1 when not grabbing.
  int group() const { return group_; }
  const std::string& name() const { return name_; }
  FemBody& body() const { return *body_; }

 private:
  // "hand 'h' on body 'b'", for messages.
  std::string label() const;

  FemBody* body_;
  std::string name_;
  HandSettings settings_;
  double speed_limit_;
  std::shared_ptr<HandPursuit> pursuit_;  // shared with the body's FrameMotion
  HandSelection selection_;
  int group_ = -1;
};

}  // namespace torsion
