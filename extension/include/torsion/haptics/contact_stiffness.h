#pragma once
// How stiffly an FEM body's contact patch resists a rigid tool (docs/haptics.md, "Tools"): the
// environment stiffness K_e of a tool's local model at 1 kHz, from the body's own step system.
// The patch is what the last solve pushed: its active node rows and face rows (a face row's load
// shared by its corners' barycentric weights), each loaded in proportion to its impulse; N is the
// direction of the net push, into the body. A load f = N w_i on the patch's nodes, every
// constrained node held, moves them by
//   dx = (dt^2 + dt beta) A^-1 f        (A = M (1 + dt alpha) + (dt^2 + dt beta) K, the step's
//                                        system: K^-1 f but for the small inertia term)
// and the patch's compliance along N is c = sum w_i N . dx_i; k_n = 1 / c (N/m). Under Hertz's
// load this is dF/dd = 2 a E*, the contact's own incremental stiffness. One CG solve,
// warm-started from the last. Simulation thread only, after the body's step.

#include <Eigen/Core>
#include <optional>
#include <unordered_map>
#include <vector>

#include "torsion/solve/projected_cg.h"

class btCollisionObject;

namespace torsion {
class FemBody;  // torsion/bullet/fem_body.h
}  // namespace torsion

namespace torsion::haptics {

struct ContactPatch {
  /// The body's nodes the last solve pushed against the tool and their shares of the push (sum 1).
  std::vector<std::pair<int, double>> load;
  Eigen::Vector3d normal;  ///< unit, the direction the tool pushes them (into the body)
  Eigen::Vector3d centre;  ///< m, where the push acts: the load's centre
};

/// The patch of `body` that `tool` pushed in the body's last step; nullopt when it pushed none.
std::optional<ContactPatch> contactPatch(const FemBody& body, const btCollisionObject& tool);

class ContactStiffness {
 public:
  /// k_n of `patch` on `body` (N/m, >= 0), with `tolerance` the CG's relative tolerance.
  double normalStiffness(FemBody& body, const ContactPatch& patch, double tolerance);

 private:
  ProjectedCg cg_;
  std::unordered_map<const FemBody*, Eigen::VectorXd> warm_;  // last solution per body
  Eigen::VectorXd load_;
};

}  // namespace torsion::haptics
