// Contact between quadratic (tet10) FEM bodies and Bullet rigid bodies: the facts the tet4 tests
// check (contact_physics_test.cpp), on bodies whose surface carries mid-edge nodes. A tet10 body's
// contact works on its refined surface (quadratic_tet_mesh.h): every boundary face split into 4
// triangles over the P2 nodes, so mid-edge nodes are surface nodes like corners; HRZ lumped
// masses make a corner node 3/16 as heavy as a mid-edge node of the same element.

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "contact_fixtures.h"
#include "resting_box.h"

namespace torsion::test {
namespace {

constexpr double kGravity = 9.81;

// A tet10 ball dropped on rigid ground at dt = 0.01 never falls through, does not bounce back up
// by more than a quarter of its fall, and comes to rest on the ground, touching it with corner
// and mid-edge nodes.
TEST(ContactTet10, DroppedBallRestsOnGround) {
  FemWorld world(contactSettings(0.01));
  addGround(world, 0.5);
  const double radius = 0.25, drop_height = 1.0;
  Result<TetMesh> mesh = makeBallTetMesh({0, 0, drop_height}, radius, 4);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  Material m = softMaterial(5e4, 500);
  m.mass_damping = 0.5;
  Result<FemBody*> added = world.addBody("ball", mesh.value(), m, Frame{}, ElementKind::kTet10);
  ASSERT_TRUE(added.ok()) << added.error().message;
  FemBody* ball = added.value();
  const int corners = ball->model().linearMeshPtr()->nodeCount();
  ASSERT_GT(ball->model().nodeCount(), corners);  // mid-edge nodes exist

  double lowest = 1e300, highest_after_impact = -1e300;
  bool touched = false;
  int mid_edge_touches = 0;        // steps in which a mid-edge node was in contact
  for (int k = 0; k < 300; ++k) {  // 3 s: falls 0.75 m (0.39 s), bounces, settles
    ASSERT_TRUE(world.step().ok) << "step " << k;
    lowest = std::min(lowest, minZ(*ball));
    touched = touched || ball->contacts().stats().active > 0;
    if (touched) highest_after_impact = std::max(highest_after_impact, centreOfMass(*ball).z());
    for (const NodeContact& c : ball->contacts().contacts()) {
      if (c.state != NodeContact::State::kInactive && c.node >= corners) {
        ++mid_edge_touches;
        break;
      }
    }
  }
  const Eigen::Vector3d c = centreOfMass(*ball);
  int corner_contacts = 0, mid_edge_contacts = 0;
  for (const NodeContact& contact : ball->contacts().contacts()) {
    if (contact.state == NodeContact::State::kInactive) continue;
    (contact.node < corners ? corner_contacts : mid_edge_contacts)++;
  }
  std::cout << "[figures] tet10 ball (" << ball->model().nodeCount() << " nodes, " << corners
            << " corners): deepest node " << lowest << " m, highest centre after impact "
            << highest_after_impact << " m, centre at rest " << c.z() << " m, contacts at rest "
            << corner_contacts << " corner + " << mid_edge_contacts << " mid-edge, steps with a "
            << "mid-edge contact " << mid_edge_touches << "\n";
  // Never through the ground, mid-edge nodes included (minZ runs over every node): 0.25 mm.
  EXPECT_GT(lowest, -1e-3 * radius);
  // Node contacts are inelastic and the ball is damped: only the elastic energy of its squash
  // lifts it again. A restitution of 0.5 would bring the centre back up by a quarter of the fall;
  // measured 3 % (2 cm of 0.75 m). A contact that pumped energy in (say through the light HRZ
  // corner nodes) would show here.
  EXPECT_LT(highest_after_impact - radius, 0.25 * (drop_height - radius));
  // At rest on it: slow (2 cm/s against an impact at 3.8 m/s), touching, the centre near one
  // radius up (squashed by its weight; the tet4 ball of the same mesh rests at 0.214 m).
  EXPECT_LT(ball->lastReport().max_speed, 0.02);
  EXPECT_LT(minZ(*ball), 1e-3 * radius);
  EXPECT_GT(c.z(), 0.8 * radius);
  EXPECT_LT(c.z(), 1.0 * radius);
  EXPECT_LT(std::hypot(c.x(), c.y()), 0.01 * radius);  // dropped straight, lands straight
  // Mid-edge nodes are surface nodes: they take part in the contact.
  EXPECT_GT(mid_edge_touches, 0);
  EXPECT_GT(corner_contacts + mid_edge_contacts, 0);
}

FemBody* addTet10Box(FemWorld& world, const std::string& name, const Eigen::Vector3d& lo,
                     const Eigen::Vector3d& hi, int nx, int ny, int nz, const Material& m) {
  Result<TetMesh> mesh = makeBoxTetMesh(lo, hi, nx, ny, nz);
  if (!mesh.ok()) {
    ADD_FAILURE() << mesh.error().message;
    return nullptr;
  }
  Result<FemBody*> body = world.addBody(name, mesh.value(), m, Frame{}, ElementKind::kTet10);
  if (!body.ok()) {
    ADD_FAILURE() << body.error().message;
    return nullptr;
  }
  return body.value();
}

// A tet10 block slides on frictionless ground into a free rigid box: the pair's horizontal
// momentum is conserved through the collision, with the block's momentum summed over its HRZ
// masses (the masses the contact solve uses), and the box leaves faster than the block.
TEST(ContactTet10, MomentumExchangedWithFreeBox) {
  FemWorld world(contactSettings(0.01));
  addGround(world, 0.0);
  FemBody* block = addTet10Box(world, "block", {-0.6, -0.15, 0.0}, {-0.3, 0.15, 0.3}, 2, 2, 2,
                               softMaterial(5e4, 200));
  ASSERT_NE(block, nullptr);
  EXPECT_TRUE((block->setVelocity({2.0, 0, 0}).ok()));
  const double box_mass = 4;
  btRigidBody* box = world.addRigidBody(std::make_unique<btBoxShape>(btVector3(0.15, 0.15, 0.15)),
                                        box_mass, at({0.0, 0, 0.15}));
  box->setFriction(0.0);
  auto px = [&] {
    return momentum(*block).x() + box_mass * toDouble(box->getLinearVelocity().x());
  };
  const double before = px();
  for (int k = 0; k < 60; ++k)  // contact at about 0.07 s, separated well before 0.6 s
    ASSERT_TRUE(world.step().ok) << "step " << k;
  const double after = px(), box_speed = box->getLinearVelocity().x();
  const double block_speed = momentum(*block).x() / block->model().totalMass();
  std::cout << "[figures] tet10 momentum: before " << before << " after " << after << " N s, box "
            << box_speed << " m/s, block " << block_speed << " m/s\n";
  // The heavier block (5.4 kg) passes momentum to the 4 kg box: the box ends faster than it.
  EXPECT_GT(box_speed, block_speed);
  EXPECT_GT(box_speed, 0.5);
  // Conserved within 1 %: the exchange is implicit and exact up to the CG tolerance.
  EXPECT_NEAR(after, before, 0.01 * std::abs(before));
  EXPECT_GT(minZ(*block), -1e-4);  // 0.1 mm: never into the ground
}

// A tet10 block on a slope (gravity tilted by theta over flat ground) with friction mu: stays put
// when tan(theta) < mu, slides with the Coulomb acceleration g (sin - mu cos) when above.
double tet10SlideDistance(double theta, double mu, double seconds) {
  WorldSettings s = contactSettings(0.01);
  s.gravity = kGravity * Eigen::Vector3d(std::sin(theta), 0, -std::cos(theta));
  FemWorld world(s);
  addGround(world, mu);
  FemBody* block = addTet10Box(world, "block", {-0.1, -0.1, 0}, {0.1, 0.1, 0.2}, 2, 2, 2,
                               softMaterial(1e5, 500));
  if (!block) return std::nan("");  // addTet10Box reported why
  const double x0 = centreOfMass(*block).x();
  const int steps = static_cast<int>(std::lround(seconds / s.solver.time_step));
  for (int k = 0; k < steps; ++k)
    EXPECT_TRUE(world.step().ok);
  EXPECT_GT(minZ(*block), -1e-4);  // 0.1 mm: never into the slope
  return centreOfMass(*block).x() - x0;
}

TEST(ContactTet10, FrictionHoldsBelowAngleSlidesAbove) {
  const double mu = 0.5, t = 1.0;  // friction angle 26.6 degrees
  const double below = tet10SlideDistance(20 * M_PI / 180, mu, t);
  const double above_theta = 35 * M_PI / 180;
  const double above = tet10SlideDistance(above_theta, mu, t);
  const double coulomb =
      0.5 * kGravity * (std::sin(above_theta) - mu * std::cos(above_theta)) * t * t;
  std::cout << "[figures] tet10 slope: 20 deg moved " << below << " m; 35 deg moved " << above
            << " m (Coulomb " << coulomb << " m)\n";
  // The tet4 test's bounds: elastic creep of a soft block only (2 mm) below the friction angle;
  // the Coulomb distance within 15 % above it (the block rocks and creeps as it starts).
  EXPECT_LT(std::abs(below), 2e-3);
  EXPECT_NEAR(above, coulomb, 0.15 * coulomb);
}

// A rigid box resting on a tet10 slab stays at rest above it (penetration within the tet4 test's
// tolerance over 4 s, every node counted), and the slab's sag matches its static equilibrium
// under the box's weight within 10 % of a mesh-converged reference. The slab and the
// box are ContactPhysics.BoxRestsOnSlabWithStaticSag's: 1 x 1 x 0.2 m, E = 20 kPa, a 20 kg box
// 0.54 m square; 8x8x2 cells, node rows 1 mm inside the box's edges (punch_reference.h).
TEST(ContactTet10, BoxRestsOnSlabWithConvergedSag) {
  PunchProblem p;
  p.punch_half_width = 0.27;
  p.load = 20 * kGravity;
  p.material = softMaterial(2e4, 100);
  const double row = p.punch_half_width - 0.001;
  const RestingBoxRun run = runRestingBox(p, 8, 2, ElementKind::kTet10, 4.0, row);
  const PunchSolution same_mesh = staticPunchSag(p, 8, 2, ElementKind::kTet10, row);
  const double reference = convergedPunchSag(p);
  std::cout << "[figures] box on tet10 slab (8x8x2, " << run.slab_nodes << " nodes): sag "
            << run.sag << " m, static on the same mesh " << same_mesh.sag << " m, converged "
            << reference << " m (" << 100 * (run.sag / reference - 1) << " %), worst penetration "
            << run.worst_penetration << " m, contacts " << run.contacts << " ("
            << run.corner_contacts << " at corners) of " << same_mesh.patch_nodes
            << " nodes under the box, largest gap under the box " << run.largest_gap_under_box
            << " m, Newton iterations max " << run.most_newton_iterations << ", unconverged steps "
            << run.unconverged_steps << "\n";
  // At rest above the slab, centred: 1 mm/s and 1 mm against a 2 cm drop settled for 4 s.
  EXPECT_LT(run.box_speed, 1e-3);
  EXPECT_LT(run.off_centre, 1e-3);
  EXPECT_LT(run.worst_penetration, 1e-4);  // 0.1 mm, against a sag of millimetres
  EXPECT_EQ(run.unconverged_steps, 0);
  // Mid-edge nodes under the box carry it. The corners may not: the rim's load goes to
  // the face contacts along the box's edges (1 mm beyond the rim row), and the 9 interior
  // corners, held bonded to a flat punch, a P2 surface's interior corners
  // pull on it (measured +0.3 N each at the sag, against -1 N pushing at the rim corners and
  // mid-edge nodes: a P2 face's corners take little or negative share of a distributed load), so
  // the unilateral contact lets them go and they hang slightly below the box. That costs no
  // support: the sag is the bonded one (below). Measured: 40 of 56 mid-edge nodes and 16 face
  // contacts at the edges (before face contacts: 16 rim corners instead), interior corners
  // 0.19 mm (4 % of the sag) below; 10 % of the sag bounds a dimple like that and not a patch of
  // the slab left behind by the box.
  EXPECT_GT(run.contacts - run.corner_contacts, 0);
  EXPECT_GT(run.corner_contacts + run.face_contacts, 0);  // the rim carries too
  EXPECT_LT(run.largest_gap_under_box, 0.1 * run.sag);
  // The dynamic rest is the same discrete slab's static equilibrium (bonded punch): see the tet4
  // test; measured 0.1 %.
  EXPECT_NEAR(run.sag, same_mesh.sag, 0.02 * same_mesh.sag);
  // Within 10 % of the converged reference (measured -7 %: the 8x8x2 mesh is still
  // stiff at the punch's edge, where the stress is singular).
  EXPECT_NEAR(run.sag, reference, 0.1 * reference);
}

}  // namespace
}  // namespace torsion::test
