// Contact between two FEM bodies (docs/contact.md, "Contact between FEM bodies"): each body's
// surface nodes against the other's surface triangles, solved with both bodies' velocities in
// one island solve. Forces, momentum, penetration and friction against their analytic values.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "surface_depth.h"
#include "torsion/analysis/surface_intersections.h"
#include "torsion/bullet/fem_body.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/mesh/ball_mesh.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion {
namespace {

std::vector<int> nodesWhere(const FemBody& body, double z_below) {
  std::vector<int> nodes;
  for (int i = 0; i < body.model().nodeCount(); ++i)
    if (body.state().position(i).z() < z_below) nodes.push_back(i);
  return nodes;
}

Eigen::Vector3d momentum(const FemBody& body) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < body.model().nodeCount(); ++i)
    p += body.model().nodeMasses()[static_cast<size_t>(i)] * body.state().velocity(i);
  return p;
}

Eigen::Vector3d centre(const FemBody& body) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int i = 0; i < body.model().nodeCount(); ++i)
    c += body.model().nodeMasses()[static_cast<size_t>(i)] * body.state().position(i);
  return c / body.model().totalMass();
}

// N: the force the pair's contacts put on `body` during the last step (impulses over dt).
Eigen::Vector3d contactForceOn(const FemWorld& world, const FemBody& body, const FemBody& other,
                               double dt) {
  const BodyPairContact* pair = world.femSolver().femContact()->pair(&body, &other);
  if (pair == nullptr) return Eigen::Vector3d::Zero();
  // The pair's first body is the one added first.
  const bool body_first = &body == world.bodies().front().get() ||
                          (&other != world.bodies().front().get() && &body < &other);
  const int na = pair->nodeCountA();
  Eigen::Vector3d impulse = Eigen::Vector3d::Zero();
  for (const SurfaceContact& c : pair->set().contacts()) {
    if (c.determined || c.state == SurfaceContact::State::kInactive) continue;
    for (size_t k = 0; k < 4; ++k)
      if ((c.nodes[k] < na) == body_first) impulse += c.beta[k] * c.multiplier;
  }
  return impulse / dt;
}

Material soft(double youngs_modulus) {
  Material m;
  m.youngs_modulus = youngs_modulus;
  m.poisson_ratio = 0.3;
  m.density = 1000;
  m.mass_damping = 2;
  return m;
}

TEST(BodyContact, ASoftBallRestsOnASoftSlabCarriedByTheTotalContactForceMg) {
  WorldSettings settings;
  settings.solver.time_step = 0.005;
  FemWorld world(settings);
  FemBody* slab =
      world
          .addBody("slab", makeBoxTetMesh({-0.3, -0.3, 0}, {0.3, 0.3, 0.1}, 6, 6, 2).value(),
                   soft(2e5))
          .value();
  slab->carryNodes(
      "base", nodesWhere(*slab, 1e-9), [](double) { return Frame{}; }, 0.0);
  FemBody* ball =
      world.addBody("ball", makeBallTetMesh({0.013, 0.021, 0.201}, 0.1, 3).value(), soft(5e4))
          .value();
  const double g = 9.81, mass = ball->model().totalMass();
  double worst_penetration = 0, tolerance = 0;
  int unconverged = 0;
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  const int steps = 400, averaged = 40;  // 2 s, the last 0.2 s averaged
  for (int k = 0; k < steps; ++k) {
    const WorldStepReport r = world.step();
    ASSERT_TRUE(r.ok) << r.message;
    const FemContactStats& s = world.femSolver().femContact()->stats();
    if (!s.converged) ++unconverged;
    worst_penetration = std::max(worst_penetration, s.max_end_penetration);
    if (k >= steps - averaged) force += contactForceOn(world, *ball, *slab, 0.005) / averaged;
  }
  tolerance = world.femSolver().femContact()->pair(slab, ball)->gapTolerance();
  const FemContactStats& s = world.femSolver().femContact()->stats();
  std::printf(
      "[figures] ball on slab: m g = %.4f N, contact force z = %.4f N (x %.2e, y %.2e), "
      "active %d, worst end penetration %.2e m (tolerance %.2e m), unconverged steps %d, "
      "last iterations %d, centre z %.5f\n",
      mass * g, force.z(), force.x(), force.y(), s.active, worst_penetration, tolerance,
      unconverged, s.iterations, centre(*ball).z());
  EXPECT_GT(s.active, 0);
  EXPECT_NEAR(force.z(), mass * g, 0.02 * mass * g);
  EXPECT_LT(std::hypot(force.x(), force.y()), 0.02 * mass * g);
  EXPECT_LE(worst_penetration, tolerance);
  EXPECT_EQ(unconverged, 0);
  // Resting on the slab's top (z = 0.1), a little sunk in by both bodies' deformation.
  EXPECT_NEAR(centre(*ball).z(), 0.2, 0.02);
}

// Two 0.1 m cubes (3 x 3 x 3 cells, E = 1 MPa, no mass damping), no gravity, dt = 1 ms: `struck`
// at rest at the origin, `thrown` 2 cm to its right (shifted 3 cm in y, 1 cm in z) moving towards
// it along -x at `speed` (m/s).
struct ThrownBlocks {
  static WorldSettings settings() {
    WorldSettings s;
    s.gravity.setZero();
    s.solver.time_step = 1e-3;
    return s;
  }
  explicit ThrownBlocks(double speed) : world(settings()) {
    Material material = soft(1e6);
    material.mass_damping = 0;
    material.stiffness_damping = 1e-3;
    struck = world
                 .addBody("struck", makeBoxTetMesh({0, 0, 0}, {0.1, 0.1, 0.1}, 3, 3, 3).value(),
                          material)
                 .value();
    thrown = world
                 .addBody("thrown",
                          makeBoxTetMesh({0.12, 0.03, 0.01}, {0.22, 0.13, 0.11}, 3, 3, 3).value(),
                          material)
                 .value();
    EXPECT_TRUE(thrown->setVelocity(Eigen::Vector3d(-speed, 0, 0)).ok());
  }
  FemWorld world;
  FemBody* struck = nullptr;
  FemBody* thrown = nullptr;
};

TEST(BodyContact, ASoftBlockThrownAtAnotherKeepsTheLinearMomentumAndDoesNotPassThrough) {
  ThrownBlocks blocks(4);
  auto& [world, struck, thrown] = blocks;
  const Eigen::Vector3d before = momentum(*struck) + momentum(*thrown);
  double worst = 0, deepest = 0;
  int unconverged = 0, contact_steps = 0;
  for (int k = 0; k < 150; ++k) {
    const WorldStepReport r = world.step();
    ASSERT_TRUE(r.ok) << r.message;
    const Eigen::Vector3d now = momentum(*struck) + momentum(*thrown);
    worst = std::max(worst, (now - before).norm() / before.norm());
    const FemContactStats& s = world.femSolver().femContact()->stats();
    if (s.active > 0) ++contact_steps;
    if (!s.converged) ++unconverged;
    deepest = std::max(deepest, s.max_end_penetration);
    // No tunnelling: no linearised end gap deeper than a millimetre (a tenth of a cell), and the
    // thrown block's centre stays a block's width right of the struck one's.
    ASSERT_LT(s.max_end_penetration, 1e-3) << "step " << k;
    ASSERT_GT(centre(*thrown).x() - centre(*struck).x(), 0.095) << "step " << k;
  }
  const double p_struck = momentum(*struck).x(), p_thrown = momentum(*thrown).x();
  std::printf(
      "[figures] thrown block: momentum %.5f -> %.5f N s (worst relative drift %.2e), "
      "struck %.4f, thrown %.4f N s, contact steps %d, unconverged %d, deepest end "
      "penetration %.2e m\n",
      before.x(), p_struck + p_thrown, worst, p_struck, p_thrown, contact_steps, unconverged,
      deepest);
  EXPECT_LT(worst, 0.01);
  EXPECT_GT(contact_steps, 0);
  EXPECT_LT(p_struck, 0.5 * before.x()) << "the struck block took a good share of the momentum";
  EXPECT_GT(centre(*thrown).x() - centre(*struck).x(), 0.1);
}

// The same blocks at 15 m/s (Bullet's Collide demo speed; 15 mm a step against 33 mm cells, the
// detection margin 1 cm): after every step and at the middle of its straight path no surface node
// of either block is inside the other beyond twice the contact's gap tolerance (a tunnelling node
// would end a step's travel inside), and the momentum holds.
TEST(BodyContact, ASoftBlockThrownAt15MetresPerSecondNeverEntersTheOther) {
  ThrownBlocks blocks(15);
  auto& [world, struck, thrown] = blocks;
  const Eigen::Vector3d before = momentum(*struck) + momentum(*thrown);
  const double limit = 2e-3 * (0.1 / 3);  // 2e-3 of a cell: about twice the gap tolerance
  double worst = 0, deepest = 0;
  int unconverged = 0, contact_steps = 0, deepest_step = 0;
  Eigen::VectorXd xs = struck->state().positions, xt = thrown->state().positions;
  for (int k = 0; k < 40; ++k) {
    const WorldStepReport r = world.step();
    ASSERT_TRUE(r.ok) << r.message;
    const FemContactStats& s = world.femSolver().femContact()->stats();
    if (s.islands > 0) ++contact_steps;
    if (!s.converged) ++unconverged;
    const Eigen::VectorXd& ys = struck->state().positions;
    const Eigen::VectorXd& yt = thrown->state().positions;
    const Eigen::VectorXd ms = 0.5 * (xs + ys), mt = 0.5 * (xt + yt);
    const TetMesh& a = struck->model().mesh();
    const TetMesh& b = thrown->model().mesh();
    const double depth =
        std::max({deepestNodeInside(a, ys, b, yt), deepestNodeInside(b, yt, a, ys),
                  deepestNodeInside(a, ms, b, mt), deepestNodeInside(b, mt, a, ms)});
    if (depth > deepest) {
      deepest = depth;
      deepest_step = k + 1;
    }
    worst =
        std::max(worst, (momentum(*struck) + momentum(*thrown) - before).norm() / before.norm());
    xs = ys;
    xt = yt;
  }
  std::printf(
      "[figures] block thrown at 15 m/s: deepest node inside the other %.2e m (step %d, limit "
      "%.2e m), momentum drift %.2e, %d of %d contact steps unconverged\n",
      deepest, deepest_step, limit, worst, unconverged, contact_steps);
  EXPECT_GT(contact_steps, 0);
  EXPECT_LT(deepest, limit);
  EXPECT_LT(worst, 0.01);
}

// Two blocks, the lower one's base fixed, the upper one (`element`) pressed down by 5 N spread
// over its top nodes, no gravity: at rest the contact carries the load.
void pressBlocks(ElementKind element) {
  WorldSettings settings;
  settings.gravity.setZero();
  settings.solver.time_step = 0.005;
  FemWorld world(settings);
  FemBody* lower =
      world.addBody("lower", makeBoxTetMesh({0, 0, 0}, {0.1, 0.1, 0.1}, 3, 3, 3).value(), soft(2e5))
          .value();
  lower->carryNodes(
      "base", nodesWhere(*lower, 1e-9), [](double) { return Frame{}; }, 0.0);
  FemBody* upper =
      world
          .addBody("upper",
                   makeBoxTetMesh({0.02, 0.01, 0.1005}, {0.08, 0.09, 0.1605}, 2, 2, 2).value(),
                   soft(2e5), Frame{}, element)
          .value();
  // 5 N down, spread over the upper block's top nodes.
  const double load = 5;
  std::vector<int> top;
  for (int i = 0; i < upper->model().nodeCount(); ++i)
    if (upper->state().position(i).z() > 0.16) top.push_back(i);
  for (int i : top)
    ASSERT_TRUE(
        upper->setNodeForce(i, Eigen::Vector3d(0, 0, -load / static_cast<double>(top.size())))
            .ok());
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  const int steps = 300, averaged = 40;
  for (int k = 0; k < steps; ++k) {
    const WorldStepReport r = world.step();
    ASSERT_TRUE(r.ok) << r.message;
    if (k >= steps - averaged) force += contactForceOn(world, *upper, *lower, 0.005) / averaged;
  }
  const FemContactStats& s = world.femSolver().femContact()->stats();
  std::printf(
      "[figures] pressed blocks (upper %s): load %.3f N, contact force on the upper block %.4f N "
      "(lateral %.2e), active %d, end penetration %.2e m, upper block speed %.2e m/s\n",
      element == ElementKind::kTet10 ? "tet10" : "tet4", load, force.z(),
      std::hypot(force.x(), force.y()), s.active, s.max_end_penetration,
      momentum(*upper).norm() / upper->model().totalMass());
  EXPECT_NEAR(force.z(), load, 0.03 * load);
  EXPECT_TRUE(s.converged);
}

TEST(BodyContact, TwoBlocksPressedTogetherCarryTheAppliedLoadThroughTheirContact) {
  pressBlocks(ElementKind::kTet4);
}

TEST(BodyContact, AQuadraticBlockPressedOnALinearOneCarriesTheLoadThroughItsSplitSurface) {
  pressBlocks(ElementKind::kTet10);
}

// A square bar (5 x 1 x 1 cells) along `axis` (0: x, 1: y), turned 45 degrees about it so that a
// ridge runs along its top and one along its bottom, centred at `centre`. 5 cells put no node at
// the middle of the ridges, where the two bars of the test below meet.
TetMesh ridgeBar(int axis, const Eigen::Vector3d& centre) {
  const double half = 0.3, side = 0.05;
  const TetMesh box = makeBoxTetMesh({-half, -side, -side}, {half, side, side}, 5, 1, 1).value();
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(axis == 0 ? 0.0 : M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
      Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitX()).toRotationMatrix();
  std::vector<Eigen::Vector3d> rest;
  for (const Eigen::Vector3d& x : box.restPositions())
    rest.push_back(centre + turn * x);
  return TetMesh(rest, box.tets());
}

// Number of steps whose end has surface triangles of the two bodies crossing (exact checker).
struct CrossedBars {
  int crossing_steps = 0;
  double top_ridge_z = 0;  // m, the falling bar's lowest point at the end
  int edge_contacts = 0;   // most edge-edge candidates in a step
};

CrossedBars dropRidgeOnRidge(bool edge_edge) {
  WorldSettings settings;
  settings.gravity.setZero();
  settings.solver.time_step = 1e-3;
  FemWorld world(settings);
  BodyContactSettings contact;
  contact.edge_edge = edge_edge;
  EXPECT_TRUE(world.femSolver().setFemContact(contact).ok());
  const double ridge = 0.05 * std::sqrt(2.0);
  FemBody* below = world.addBody("below", ridgeBar(0, Eigen::Vector3d::Zero()), soft(1e6)).value();
  below->carryNodes(
      "base", nodesWhere(*below, -ridge + 1e-9), [](double) { return Frame{}; }, 0.0);
  FemBody* above =
      world.addBody("above", ridgeBar(1, Eigen::Vector3d(0, 0, 2 * ridge + 0.005)), soft(1e6))
          .value();
  EXPECT_TRUE(above->setVelocity(Eigen::Vector3d(0, 0, -1)).ok());
  CrossedBars result;
  for (int k = 0; k < 60; ++k) {
    const WorldStepReport r = world.step();
    EXPECT_TRUE(r.ok) << r.message;
    if (!findSurfaceIntersections(
             below->model().mesh().surfaceTriangles(), below->state().positions,
             above->model().mesh().surfaceTriangles(), above->state().positions)
             .empty())
      ++result.crossing_steps;
    if (const BodyPairContact* pair = world.femSolver().femContact()->pair(below, above)) {
      int edges = 0;
      for (const SurfaceContact& c : pair->set().contacts())
        edges += c.edge >= 0 ? 1 : 0;
      result.edge_contacts = std::max(result.edge_contacts, edges);
    }
  }
  result.top_ridge_z = 1e9;
  for (int i = 0; i < above->model().nodeCount(); ++i)
    result.top_ridge_z = std::min(result.top_ridge_z, above->state().position(i).z());
  return result;
}

TEST(BodyContact, ARidgeDroppedAcrossAnotherRidgeIsStoppedByItsEdgeWhereNoNodeMeetsAFace) {
  // Two square bars turned 45 degrees, one held, the other thrown down at 1 m/s across it at a
  // right angle: ridge meets ridge in the middle of two edges, 6 cm from any node. Node-triangle
  // contact alone sees nothing until a node reaches the other's face (the ridges already 4 cm
  // through each other); the edge pair holds them apart at the ridge.
  const CrossedBars without = dropRidgeOnRidge(false);
  const CrossedBars with = dropRidgeOnRidge(true);
  const double ridge = 0.05 * std::sqrt(2.0);
  std::printf(
      "[figures] ridge on ridge: node-triangle only: %d of 60 steps crossing, lowest "
      "point %.4f m; with edge pairs: %d crossing, lowest point %.4f m, up to %d edge "
      "pairs (the held ridge at %.4f m)\n",
      without.crossing_steps, without.top_ridge_z, with.crossing_steps, with.top_ridge_z,
      with.edge_contacts, ridge);
  EXPECT_GT(without.crossing_steps, 0);  // the case edge pairs are for
  EXPECT_EQ(with.crossing_steps, 0);
  EXPECT_GT(with.edge_contacts, 0);
  // Held at the ridge (within a millimetre, the bars' deformation), not at a face 4 cm below.
  EXPECT_GT(with.top_ridge_z, ridge - 1e-3);
}

// Two soft blocks side by side, pressed against each other, and a 2 kg rigid box resting across
// both: one island of two FEM bodies with one dynamic rigid body that both touch. The box is one
// body of the island (solved once with both blocks' contacts, its velocity applied once): it
// settles, and the blocks' contacts carry its weight between them, split by symmetry.
TEST(BodyContact, ARigidBoxAcrossTwoTouchingSoftBlocksIsOneBodyOfTheirIsland) {
  WorldSettings settings;
  settings.solver.time_step = 0.005;
  FemWorld world(settings);
  FemBody* left =
      world
          .addBody("left", makeBoxTetMesh({-0.2, -0.1, 0}, {0, 0.1, 0.1}, 4, 4, 2).value(),
                   soft(2e5))
          .value();
  FemBody* right =
      world
          .addBody("right", makeBoxTetMesh({0, -0.1, 0}, {0.2, 0.1, 0.1}, 4, 4, 2).value(),
                   soft(2e5))
          .value();
  for (FemBody* block : {left, right})
    block->carryNodes(
        "base", nodesWhere(*block, 1e-9), [](double) { return Frame{}; }, 0.0);
  btTransform start;
  start.setIdentity();
  start.setOrigin(btVector3(0, 0, btScalar(0.1 + 0.025 + 1e-4)));
  btRigidBody* box = world.addRigidBody(
      std::make_unique<btBoxShape>(btVector3(btScalar(0.15), btScalar(0.05), btScalar(0.025))), 2.0,
      start);
  double fastest = 0, drift = 0;
  int unconverged = 0, islands = 0;
  const int steps = 400;  // 2 s
  for (int k = 0; k < steps; ++k) {
    const WorldStepReport r = world.step();
    ASSERT_TRUE(r.ok) << r.message;
    const FemContactStats& s = world.femSolver().femContact()->stats();
    if (!s.converged) ++unconverged;
    islands = std::max(islands, s.islands);
    if (k * settings.solver.time_step >= 1.0) {
      fastest = std::max(fastest, static_cast<double>(box->getLinearVelocity().length()));
      drift += static_cast<double>(box->getLinearVelocity().x()) / (steps / 2);
    }
  }
  const double g = 9.81, dt = settings.solver.time_step;
  // The box's weight, as the two blocks' rigid contacts carry it (their normal impulses over dt:
  // the contacts under a flat box are vertical).
  const double on_left = left->contacts().stats().normal_impulse;
  const double on_right = right->contacts().stats().normal_impulse;
  std::printf(
      "[figures] box across two soft blocks: islands %d, unconverged steps %d, fastest after 1 s "
      "%.2e m/s, drift %.2e m/s, box weight %.4f N carried %.4f (left) + %.4f (right) N\n",
      islands, unconverged, fastest, drift, 2 * g, on_left / dt, on_right / dt);
  EXPECT_EQ(islands, 1) << "the blocks touch: one island";
  EXPECT_EQ(unconverged, 0);
  EXPECT_LT(fastest, 1e-3) << "it rests";
  EXPECT_LT(std::abs(drift), 1e-4);
  EXPECT_NEAR((on_left + on_right) / dt, 2 * g, 0.01 * 2 * g);
  EXPECT_NEAR(on_left, on_right, 0.05 * (on_left + on_right)) << "split by symmetry";
}

}  // namespace
}  // namespace torsion

namespace torsion {
namespace {

// Two blocks gliding past each other 4 mm apart (within the candidates' margin of a quarter of
// the 5 cm cells, never touching): the pair has candidates every step and the island is solved
// as one problem, but no row pushes, and each block moves as it does alone in a world of its own
// to within the difference between the island's tolerance (1e-6) and the solver's (1e-4): 1e-4
// of the distance travelled (measured 4e-5).
TEST(BodyContact, BlocksPassingWithinTheMarginMoveAsTheyDoAlone) {
  WorldSettings settings;
  settings.gravity.setZero();
  settings.solver.time_step = 0.01;
  settings.solver.threads = 1;
  const TetMesh lower = makeBoxTetMesh({0, 0, 0}, {0.2, 0.2, 0.1}, 4, 4, 2).value();
  const TetMesh upper = makeBoxTetMesh({0, 0, 0.104}, {0.2, 0.2, 0.204}, 4, 4, 2).value();
  FemWorld both(settings), alone_lower(settings), alone_upper(settings);
  FemBody* a = both.addBody("lower", lower, soft(1e5)).value();
  FemBody* b = both.addBody("upper", upper, soft(1e5)).value();
  FemBody* a_alone = alone_lower.addBody("lower", lower, soft(1e5)).value();
  FemBody* b_alone = alone_upper.addBody("upper", upper, soft(1e5)).value();
  for (FemBody* body : {b, b_alone})
    ASSERT_TRUE(body->setVelocity({0.5, 0, 0}).ok());
  int candidate_steps = 0;
  for (int k = 0; k < 30; ++k) {
    ASSERT_TRUE(both.step().ok);
    ASSERT_TRUE(alone_lower.step().ok);
    ASSERT_TRUE(alone_upper.step().ok);
    const FemContactStats& s = both.femSolver().femContact()->stats();
    if (s.candidates > 0) ++candidate_steps;
    EXPECT_EQ(s.active, 0) << "step " << k;
    EXPECT_TRUE(s.converged);
  }
  const double apart_a = (a->state().positions - a_alone->state().positions).cwiseAbs().maxCoeff();
  const double apart_b = (b->state().positions - b_alone->state().positions).cwiseAbs().maxCoeff();
  std::printf("[figures] blocks passing within the margin: %g / %g m from alone\n", apart_a,
              apart_b);
  // The upper block slows by its mass damping (2 /s): 0.25 (1 - e^-0.6) = 0.112 m in 0.3 s.
  const double travelled = b->state().position(0).x();
  EXPECT_NEAR(travelled, 0.25 * (1 - std::exp(-0.6)), 2e-3);
  EXPECT_EQ(candidate_steps, 30);
  EXPECT_LT(apart_a, 1e-4 * travelled);
  EXPECT_LT(apart_b, 1e-4 * travelled);
}

}  // namespace
}  // namespace torsion
