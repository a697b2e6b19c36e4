#pragma once
// The contacts of a PyWorld's last step, listed as PyBullet's getContactPoints lists them: the two
// bodies, a point, the normal, the impulse. Python-free; World.contacts() (bind_world.cpp) makes
// numpy arrays of it. Two kinds are listed, each where the library keeps it after a step:
//   - an FEM body's nodes and surface faces against rigid bodies (RigidContactSolver::contacts()
//     and solvedFaceContacts(): those that gave an impulse; anchors are not contacts);
//   - rigid bodies against each other (Bullet's persistent manifolds: points that touch or that
//     carried an impulse).
// Contact between FEM bodies and self-contact are not listed: their impulses live in their
// surface contact sets (contact/surface_contact_set.h) as multipliers.

#include <string>
#include <vector>

#include "py_world.h"

namespace torsion::python {

/// Row k of each array is one contact. A is the FEM body in FEM-rigid contact, else Bullet's
/// first body of the pair.
struct ContactList {
  std::vector<std::string> body_a, body_b;  ///< names: a body, a rigid body or "ground"
  std::vector<double> points;               ///< 3 per contact, m: on A, at the end of the step
  std::vector<double> normals;              ///< 3 per contact: unit, from B towards A
  std::vector<double> impulses;             ///< 3 per contact, N s: what B gave A over the step
  size_t size() const { return body_a.size(); }
};

/// The contacts of the last step taken; empty before the first step and after restoreState()
/// until the next step (PyWorld::stepped()).
ContactList lastStepContacts(PyWorld& world);

}  // namespace torsion::python
