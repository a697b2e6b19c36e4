#pragma once
// A hand acting on one FEM body through the hand plane (DESIGN.md section 3; the report's
// Algorithms 1 and 2).
//
//   Hand hand(*body);
//   Result<int> n = hand.grab(device_frame, world.time());   // Initialize(O, R)
//   while (...) {
//     hand.moveTo(next_device_frame);   // the pose at the END of the next step
//     world.step();                     // Update: nodes land on R p_hat + O
//     Wrench w = hand.wrench();         // what the body pushes back with, about O
//   }
//   hand.release();
//
// grab() selects the patch (selectGrabbedPatch) at the body's current positions and hands its
// nodes to FemBody::carryNodes with a FrameMotion that reads the hand's target frame; the body's
// CarriedNodes prescribe them, each step from t to t + dt, to R p_hat + O of that frame in
// position and velocity. The motion ignores its time argument: the target is whatever moveTo set
// last, so a frame given to moveTo is where the grabbed nodes are at the end of the next step, and
// they stay there until moveTo is called again. Smoothing a fast device (substeps, rate limits)
// belongs to the caller.
//
// Simulation thread only, like the body. The body must outlive the hand's calls. Destroying a
// grabbing hand does not touch the body: its nodes stay held at the last target (the motion owns
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

class Hand {
 public:
  /// A hand acting on `body`; `name` names its node groups in the body ("hand" by default).
  explicit Hand(FemBody& body, std::string name = "hand");
  Hand(const Hand&) = delete;  // one hand, one node group: hold it by pointer to share it
  Hand& operator=(const Hand&) = delete;

  /// Initialize(O, R): selects the patch at the body's current positions, stores
  /// p_hat = R^T (p - O) for each of its nodes and starts carrying them by this hand's frame,
  /// which becomes `frame`. Returns the number of grabbed nodes, or an Error with the selection's
  /// message (the plane misses the body, or the ray from O along i misses every cut triangle);
  /// then nothing is grabbed. A hand that already holds a patch releases it first. `now` is the
  /// world's time (FemWorld::time()).
  Result<int> grab(const Frame& frame, double now);

  /// Update(O, R): the target frame, i.e. the pose of the hand at the end of the next step.
  /// Has no effect on the body until the next step; harmless when not grabbing.
  void moveTo(const Frame& frame);

  /// Lets go: the grabbed nodes are free from the next step on (FemBody::releaseGroup). The hand
  /// may grab again, elsewhere. No-op when not grabbing.
  void release();

  bool grabbed() const { return group_ >= 0; }

  /// The force and torque (about the target frame's origin O) that the body exerted on the grabbed
  /// nodes at the end of the last step; zero when not grabbing or before the body's first step.
  /// Read it before moveTo() so that O is the origin the nodes were carried to.
  Wrench wrench() const;

  /// The grabbed nodes, ascending; empty when not grabbing.
  const std::vector<int>& grabbedNodes() const;
  /// The selection of the last grab() (also when it failed).
  const HandSelection& selection() const { return selection_; }
  /// The target frame (the last one given to grab() or moveTo()).
  const Frame& frame() const { return *target_; }
  /// The body's node group carrying the patch, or -1 when not grabbing.
  int group() const { return group_; }
  const std::string& name() const { return name_; }
  FemBody& body() const { return *body_; }

 private:
  FemBody* body_;
  std::string name_;
  std::shared_ptr<Frame> target_;  // shared with the body's FrameMotion
  HandSelection selection_;
  int group_ = -1;
};

}  // namespace torsion
