#pragma once
// A rigid box dropped 2 cm onto a deformable slab (bottom fixed) and left to rest: the run behind
// the resting-box tests for tet4 and tet10 slabs. The slab is meshed as the static reference's
// (punch_reference.h), node rows under the box's edges, so the dynamic sag and the reference
// describe the same footprint.

#include <algorithm>
#include <cmath>
#include <memory>

#include "contact_fixtures.h"
#include "punch_reference.h"
#include "torsion/contact/shape_distance.h"

namespace torsion::test {

struct RestingBoxRun {
  double sag = 0;                ///< m, slab top minus the box's bottom face at the end
  double worst_penetration = 0;  ///< m, deepest slab node inside the box over the whole run
  double box_speed = 0;          ///< m/s, at the end
  double off_centre = 0;         ///< m, horizontal drift of the box's centre
  int contacts = 0;              ///< active node contacts at the end
  int face_contacts = 0;         ///< face contacts (docs/contact-pipeline.md), not in `contacts`
  int corner_contacts = 0;       ///< of which at nodes of the linear mesh (tet10: element corners)
  /// m, at the end: the largest distance of a node under the box (top nodes within its
  /// footprint) below the box's bottom face: how well the slab's surface follows the box.
  double largest_gap_under_box = 0;
  int slab_nodes = 0;
  int most_newton_iterations = 0;  ///< per step, over the run
  int unconverged_steps = 0;       ///< the contact solve did not converge
  long cg_iterations = 0;          ///< over the run
};

/// `p` gives the slab, the box's footprint (half-width c) and weight; the box is 0.1 m high and
/// starts 2 cm above the slab. The slab's node rows are at +-`row` (punchSlabMesh). Steps of
/// 0.01 s for `seconds`.
inline RestingBoxRun runRestingBox(const PunchProblem& p, int cells_across, int cells_thick,
                                   ElementKind element, double seconds, double row) {
  const double box_half_height = 0.05, box_mass = p.load / p.gravity;
  FemWorld world(contactSettings(0.01));
  Result<FemBody*> added = world.addBody("slab", punchSlabMesh(p, cells_across, cells_thick, row),
                                         p.material, Frame{}, element);
  if (!added.ok()) {
    ADD_FAILURE() << added.error().message;
    return {};
  }
  FemBody* slab = added.value();
  std::vector<int> base;
  for (int i = 0; i < slab->model().nodeCount(); ++i) {
    if (slab->state().position(i).z() < 1e-9) base.push_back(i);
  }
  slab->carryNodes(
      "base", base, [](double) { return Frame{}; }, 0.0);
  const double c = p.punch_half_width;
  btRigidBody* box =
      world.addRigidBody(std::make_unique<btBoxShape>(btVector3(c, c, box_half_height)), box_mass,
                         at({0, 0, p.top + box_half_height + 0.02}));
  box->setFriction(1.0);  // sticking, as the bonded reference assumes

  RestingBoxRun run;
  run.slab_nodes = slab->model().nodeCount();
  const int steps = static_cast<int>(std::lround(seconds / 0.01));
  for (int k = 0; k < steps; ++k) {
    const WorldStepReport r = world.step();
    EXPECT_TRUE(r.ok) << "step " << k << ": " << r.message;
    if (!r.ok) break;
    const ContactStepStats& stats = slab->contacts().stats();
    run.most_newton_iterations = std::max(run.most_newton_iterations, stats.newton_iterations);
    if (!stats.converged) ++run.unconverged_steps;
    run.cg_iterations += slab->lastReport().solve.iterations;
    // Measured on the geometry after each step, every node (tet10: mid-edge nodes too).
    for (int i = 0; i < slab->model().nodeCount(); ++i) {
      auto d = signedDistance(*box->getCollisionShape(), box->getWorldTransform(),
                              slab->state().position(i), 0);
      if (d) run.worst_penetration = std::max(run.worst_penetration, -d->distance);
    }
  }
  const Eigen::Vector3d centre = toEigen(box->getCenterOfMassPosition());
  run.sag = p.top - (centre.z() - box_half_height);
  run.box_speed = toEigen(box->getLinearVelocity()).norm();
  run.off_centre = std::hypot(centre.x(), centre.y());
  // Node contacts (face contacts are counted apart: they hold the box's edges between nodes).
  run.contacts = slab->contacts().stats().active - slab->contacts().stats().face_active;
  run.face_contacts = slab->contacts().stats().face_active;
  const int corners = slab->model().linearMeshPtr()->nodeCount();  // P2 nodes come after them
  for (const NodeContact& contact : slab->contacts().contacts()) {
    if (contact.state != NodeContact::State::kInactive && contact.node < corners)
      ++run.corner_contacts;
  }
  const double bottom = centre.z() - box_half_height;
  for (int i = 0; i < slab->model().nodeCount(); ++i) {
    const Eigen::Vector3d& x0 = slab->model().mesh().restPositions()[static_cast<size_t>(i)];
    if (x0.z() > p.top - 1e-9 && std::abs(x0.x()) <= c && std::abs(x0.y()) <= c) {
      run.largest_gap_under_box =
          std::max(run.largest_gap_under_box, bottom - slab->state().position(i).z());
    }
  }
  return run;
}

}  // namespace torsion::test
