// The hand plane (docs/design.md section 3): the grabbed patch against a brute-force reference on a
// cylinder and a U, the on-plane rule, and a Hand carrying a twist, letting go and grabbing again.
#include "torsion/constraints/hand_plane.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <string>

#include "torsion/bullet/fem_world.h"
#include "torsion/bullet/hand.h"
#include "torsion/mesh/box_mesh.h"
#include "torsion/mesh/mesh_io.h"

namespace torsion {
namespace {

// cylinder_2430: r = 1, L = 10 along +z; its lateral surface is an 11-gon with rings of 11 nodes
// every 10/34 m (and a few extra nodes at the centres of some of its quads).
constexpr double kInradius = 0.95949297361449737;  // cos(pi / 11)
const TetMesh& cylinder() {
  static const TetMesh mesh =
      readMesh(std::string(TORSION_ASSETS_DIR) + "/cylinder_2430.node").value().mesh;
  return mesh;
}

Eigen::VectorXd restPositionsOf(const TetMesh& mesh) {
  Eigen::VectorXd x(3 * mesh.nodeCount());
  for (int n = 0; n < mesh.nodeCount(); ++n)
    x.segment<3>(3 * n) = mesh.restPositions()[static_cast<size_t>(n)];
  return x;
}

Frame makeFrame(const Eigen::Vector3d& origin,
                const Eigen::Quaterniond& rotation = Eigen::Quaterniond::Identity()) {
  Frame f;
  f.origin = origin;
  f.rotation = rotation;
  return f;
}

Eigen::Quaterniond about(const Eigen::Vector3d& axis, double angle) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()));
}

Eigen::Vector3d vertex(const Eigen::VectorXd& x, int n) {
  return x.segment<3>(3 * n);
}

std::vector<int> verticesOf(const TetMesh& mesh, const std::vector<int>& triangles) {
  std::vector<int> nodes;
  for (int t : triangles) {
    const Triangle& tri = mesh.surfaceTriangles()[static_cast<size_t>(t)];
    nodes.insert(nodes.end(), tri.begin(), tri.end());
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  return nodes;
}

// ---- brute-force reference, independent of TetMesh's adjacency and of the Moller-Trumbore test

struct Reference {
  std::vector<int> cut;                                        // every cut triangle, ascending
  std::map<int, int> component_of;                             // cut triangle -> component id
  double first_hit = std::numeric_limits<double>::infinity();  // along the ray, in the plane
};

int findRoot(std::vector<int>& parent, int a) {
  while (parent[static_cast<size_t>(a)] != a)
    a = parent[static_cast<size_t>(a)] =
        parent[static_cast<size_t>(parent[static_cast<size_t>(a)])];
  return a;
}

Reference bruteForce(const TetMesh& mesh, const Eigen::VectorXd& x, const Frame& frame) {
  const Eigen::Matrix3d R = frame.rotation.toRotationMatrix();
  const Eigen::Vector3d O = frame.origin, i = R.col(0), j = R.col(1), k = R.col(2);
  const auto& tris = mesh.surfaceTriangles();
  Reference ref;
  for (int t = 0; t < mesh.surfaceTriangleCount(); ++t) {
    const Triangle& tri = tris[static_cast<size_t>(t)];
    if (triangleCutByPlane(vertex(x, tri[0]), vertex(x, tri[1]), vertex(x, tri[2]), O, k))
      ref.cut.push_back(t);
  }
  // Components: union-find over pairs of cut triangles that share two vertices (an edge).
  const size_t m = ref.cut.size();
  std::vector<int> parent(m);
  std::iota(parent.begin(), parent.end(), 0);
  for (size_t a = 0; a < m; ++a) {
    for (size_t b = a + 1; b < m; ++b) {
      const Triangle& ta = tris[static_cast<size_t>(ref.cut[a])];
      const Triangle& tb = tris[static_cast<size_t>(ref.cut[b])];
      int shared = 0;
      for (int va : ta)
        shared += static_cast<int>(std::count(tb.begin(), tb.end(), va));
      if (shared >= 2)
        parent[static_cast<size_t>(findRoot(parent, static_cast<int>(a)))] =
            findRoot(parent, static_cast<int>(b));
    }
  }
  for (size_t a = 0; a < m; ++a)
    ref.component_of[ref.cut[a]] = findRoot(parent, static_cast<int>(a));

  // First hit: in the plane's coordinates (u, v) = (i, j).(p - O), each cut triangle meets the
  // plane in a segment between the points where its edges change side; the ray is v = 0, u >= 0.
  for (int t : ref.cut) {
    const Triangle& tri = tris[static_cast<size_t>(t)];
    std::vector<Eigen::Vector2d> ends;
    for (size_t e = 0; e < 3; ++e) {
      const Eigen::Vector3d p = vertex(x, tri[e]), q = vertex(x, tri[(e + 1) % 3]);
      if (onPositiveSide(p, O, k) == onPositiveSide(q, O, k)) continue;
      const double dp = k.dot(p - O), dq = k.dot(q - O);
      const double s = dp == dq ? 0.0 : std::clamp(dp / (dp - dq), 0.0, 1.0);
      const Eigen::Vector3d c = p + s * (q - p);
      ends.emplace_back(i.dot(c - O), j.dot(c - O));
    }
    if (ends.size() != 2) continue;
    const Eigen::Vector2d a = ends[0], b = ends[1];
    const double tol = 1e-9;
    double u = std::numeric_limits<double>::infinity();
    if (std::abs(a.y()) <= tol && std::abs(b.y()) <= tol) {
      u = std::max(0.0, std::min(a.x(), b.x()));
      if (std::max(a.x(), b.x()) < -tol) u = std::numeric_limits<double>::infinity();
    } else if ((a.y() <= tol && b.y() >= -tol) || (a.y() >= -tol && b.y() <= tol)) {
      u = a.x() + (b.x() - a.x()) * a.y() / (a.y() - b.y());
      if (u < -tol) u = std::numeric_limits<double>::infinity();
    }
    ref.first_hit = std::min(ref.first_hit, u);
  }
  return ref;
}

// Runs the selection and checks it against the brute-force reference; returns it for more checks.
HandSelection expectMatchesBruteForce(const TetMesh& mesh, const Eigen::VectorXd& x,
                                      const Frame& frame, const std::string& label) {
  SCOPED_TRACE(label);
  const HandSelection sel = selectGrabbedPatch(mesh, x, frame);
  const Reference ref = bruteForce(mesh, x, frame);
  EXPECT_FALSE(sel.message.empty());
  EXPECT_EQ(sel.cut_triangle_count, static_cast<int>(ref.cut.size()));
  if (ref.cut.empty()) {
    EXPECT_EQ(sel.status, HandSelectionStatus::kNoTriangleCut) << sel.message;
    EXPECT_TRUE(sel.nodes.empty());
    return sel;
  }
  if (!std::isfinite(ref.first_hit)) {
    EXPECT_EQ(sel.status, HandSelectionStatus::kRayMissed) << sel.message;
    EXPECT_TRUE(sel.nodes.empty());
    return sel;
  }
  EXPECT_EQ(sel.status, HandSelectionStatus::kGrabbed) << sel.message;
  if (sel.status != HandSelectionStatus::kGrabbed) return sel;
  EXPECT_NEAR(sel.hit_distance, ref.first_hit, 1e-9);
  EXPECT_LT(
      (sel.hit_point - (frame.origin + sel.hit_distance * frame.rotation.toRotationMatrix().col(0)))
          .norm(),
      1e-12);
  EXPECT_TRUE(ref.component_of.count(sel.hit_triangle));
  std::vector<int> expected;
  const int component = ref.component_of.at(sel.hit_triangle);
  for (const auto& [t, c] : ref.component_of) {
    if (c == component) expected.push_back(t);
  }
  EXPECT_EQ(sel.triangles, expected);
  EXPECT_EQ(sel.nodes, verticesOf(mesh, expected));
  return sel;
}

// ---- the on-plane rule and the ray test

TEST(HandPlane, OnPlaneVerticesCountAsPositiveSide) {
  const Eigen::Vector3d O(0, 0, 1), k(0, 0, 1);
  auto cut = [&](double za, double zb, double zc) {
    return triangleCutByPlane({0, 0, za}, {1, 0, zb}, {0, 1, zc}, O, k);
  };
  EXPECT_TRUE(cut(0, 2, 2));  // strictly on both sides
  EXPECT_TRUE(cut(0, 0, 2));
  EXPECT_FALSE(cut(2, 3, 4));  // all above
  EXPECT_FALSE(cut(0, -1, 0.5));
  EXPECT_TRUE(cut(1, 0, 0));   // touches at a vertex, the rest below: cut
  EXPECT_FALSE(cut(1, 2, 2));  // touches at a vertex, the rest above: not cut
  EXPECT_TRUE(cut(1, 1, 0));   // an edge on the plane, the rest below: cut
  EXPECT_FALSE(cut(1, 1, 2));  // an edge on the plane, the rest above: not cut
  EXPECT_FALSE(cut(1, 1, 1));  // lying in the plane: not cut
  // Flipping the normal flips the touching cases, not the clear ones.
  EXPECT_FALSE(triangleCutByPlane({0, 0, 1}, {1, 0, 0}, {0, 1, 0}, O, -k));
  EXPECT_TRUE(triangleCutByPlane({0, 0, 1}, {1, 0, 2}, {0, 1, 2}, O, -k));
  EXPECT_TRUE(triangleCutByPlane({0, 0, 0}, {1, 0, 2}, {0, 1, 2}, O, -k));
  // Round-off of a rotated frame is on the plane; a real offset is not.
  EXPECT_TRUE(onPositiveSide({5, 0, 1 - 1e-15}, O, k));
  EXPECT_FALSE(onPositiveSide({5, 0, 1 - 1e-9}, O, k));
}

TEST(HandPlane, RayHitsInteriorEdgesAndVerticesButNotBehindOrParallel) {
  const Eigen::Vector3d a(1, 0, 0), b(1, 1, 0), c(1, 0, 1);  // in the plane x = 1
  const Eigen::Vector3d x(1, 0, 0);
  auto hit = [&](const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
    return rayHitsTriangle(o, d, a, b, c);
  };
  ASSERT_TRUE(hit({0, 0.25, 0.25}, x));
  EXPECT_NEAR(*hit({0, 0.25, 0.25}, x), 1.0, 1e-15);
  ASSERT_TRUE(hit({-1, 0, 0}, x));  // through vertex a
  EXPECT_NEAR(*hit({-1, 0, 0}, x), 2.0, 1e-15);
  EXPECT_TRUE(hit({0, 0.5, 0}, x));                              // through edge ab
  EXPECT_TRUE(hit({0, 0.5, 0.5}, x));                            // through edge bc
  EXPECT_FALSE(hit({0, 0.6, 0.6}, x));                           // beside it
  EXPECT_FALSE(hit({2, 0.25, 0.25}, x));                         // behind the origin
  EXPECT_FALSE(hit({0, 0.25, 0.25}, Eigen::Vector3d(0, 1, 0)));  // parallel
  // Double the direction: t halves (t is along the direction vector as given).
  EXPECT_NEAR(*hit({0, 0.25, 0.25}, 2 * x), 0.5, 1e-15);
}

// ---- the cylinder

TEST(HandPlane, CylinderRingsMatchBruteForce) {
  const TetMesh& mesh = cylinder();
  const Eigen::VectorXd x = restPositionsOf(mesh);
  // A layer of surface nodes near the middle: the plane through it exactly.
  double layer = -1;
  for (int n : mesh.surfaceNodes()) {
    const double z = x(3 * n + 2);
    if (z > 4 && z < 6) {
      layer = z;
      break;
    }
  }
  ASSERT_GT(layer, 0);
  const double h = 10.0 / 34.0;  // the spacing of the node rings
  for (double c : {layer, 0.37, 5.0, 9.99}) {
    const HandSelection sel =
        expectMatchesBruteForce(mesh, x, makeFrame({0, 0, c}), "z = " + std::to_string(c));
    ASSERT_EQ(sel.status, HandSelectionStatus::kGrabbed);
    // Away from the caps the plane cuts only lateral triangles, all connected: the whole ring
    // (the band of the 11-gon between two node rings, with the mesher's extra points on some of
    // its faces).
    EXPECT_EQ(static_cast<int>(sel.triangles.size()), sel.cut_triangle_count);
    EXPECT_GE(sel.triangles.size(), 22u);
    EXPECT_GE(sel.nodes.size(), 22u);
    // The ray from the axis along +x meets the 11-gon at distance cos(pi/11) .. 1.
    EXPECT_GE(sel.hit_distance, kInradius - 1e-12);
    EXPECT_LE(sel.hit_distance, 1 + 1e-12);
    for (int n : sel.nodes) {
      EXPECT_LT(std::abs(x(3 * n + 2) - c), 2 * h + 1e-9) << "c = " << c;
      EXPECT_GE(x.segment<2>(3 * n).norm(), kInradius - 1e-9);  // lateral, not a cap's inside
    }
    // The on-plane rule: the plane counts as moved slightly along -k. Through a node layer, it
    // selects what the plane 1e-7 m lower selects: the band just below the layer.
    const HandSelection lower = selectGrabbedPatch(mesh, x, makeFrame({0, 0, c - 1e-7}));
    EXPECT_EQ(sel.triangles, lower.triangles) << "c = " << c;
  }
  // ... and not what the plane 1e-7 m higher selects (the band above).
  const HandSelection above = selectGrabbedPatch(mesh, x, makeFrame({0, 0, layer + 1e-7}));
  const HandSelection on = selectGrabbedPatch(mesh, x, makeFrame({0, 0, layer}));
  EXPECT_NE(on.triangles, above.triangles);
}

TEST(HandPlane, ObliquePlanesMatchBruteForce) {
  const TetMesh& mesh = cylinder();
  const Eigen::VectorXd x = restPositionsOf(mesh);
  const double tilt = M_PI / 6;
  const std::vector<Eigen::Vector3d> axes = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                             Eigen::Vector3d(1, 1, 0)};
  for (const Eigen::Vector3d& axis : axes) {
    const HandSelection sel = expectMatchesBruteForce(
        mesh, x, makeFrame({0, 0, 5}, about(axis, tilt)), "tilt about " + std::to_string(axis.y()));
    ASSERT_EQ(sel.status, HandSelectionStatus::kGrabbed);
    EXPECT_EQ(static_cast<int>(sel.triangles.size()), sel.cut_triangle_count);  // one ring
    EXPECT_GT(sel.triangles.size(), 22u);  // an ellipse crosses more triangles than a circle
  }
  // Tilted near the top, the plane also cuts the end cap: the patch runs across it.
  const HandSelection top = expectMatchesBruteForce(
      mesh, x, makeFrame({0, 0, 9.7}, about(Eigen::Vector3d::UnitX(), tilt)),
      "tilted through the cap");
  ASSERT_EQ(top.status, HandSelectionStatus::kGrabbed);
  bool cap_node = false;
  for (int n : top.nodes)
    cap_node = cap_node || x.segment<2>(3 * n).norm() < 0.99;
  EXPECT_TRUE(cap_node);
  // And a plane through O off the axis with a generic orientation.
  expectMatchesBruteForce(
      mesh, x, makeFrame({0.3, -0.2, 3.3}, about(Eigen::Vector3d(0.2, -0.7, 0.4), 0.9)), "generic");
}

TEST(HandPlane, RayFromOutsideGrabsWhenPointingAtTheBodyOnly) {
  const TetMesh& mesh = cylinder();
  const Eigen::VectorXd x = restPositionsOf(mesh);
  // O at x = 3, i = -x (a half turn about z): the ray enters the near side.
  const HandSelection toward = expectMatchesBruteForce(
      mesh, x, makeFrame({3, 0, 5}, about(Eigen::Vector3d::UnitZ(), M_PI)), "toward");
  ASSERT_EQ(toward.status, HandSelectionStatus::kGrabbed);
  EXPECT_GE(toward.hit_distance, 2 - 1e-12);
  EXPECT_LE(toward.hit_distance, 3 - kInradius + 1e-12);
  EXPECT_EQ(static_cast<int>(toward.triangles.size()), toward.cut_triangle_count);  // the ring
  // Pointing away: the plane cuts the body but the ray hits nothing.
  const HandSelection away = expectMatchesBruteForce(mesh, x, makeFrame({3, 0, 5}), "away");
  EXPECT_EQ(away.status, HandSelectionStatus::kRayMissed);
  EXPECT_GT(away.cut_triangle_count, 0);
  EXPECT_NE(away.message.find("ray hits none"), std::string::npos) << away.message;
  // From x = -3 along +x the first hit is the near side (x ~ -1), not the far one.
  const HandSelection through = expectMatchesBruteForce(mesh, x, makeFrame({-3, 0, 5}), "through");
  ASSERT_EQ(through.status, HandSelectionStatus::kGrabbed);
  EXPECT_LT(through.hit_point.x(), -0.9);
}

TEST(HandPlane, PlaneBesideOrOnACapFace) {
  const TetMesh& mesh = cylinder();
  const Eigen::VectorXd x = restPositionsOf(mesh);
  const HandSelection beyond = expectMatchesBruteForce(mesh, x, makeFrame({0, 0, 20}), "z = 20");
  EXPECT_EQ(beyond.status, HandSelectionStatus::kNoTriangleCut);
  EXPECT_EQ(beyond.cut_triangle_count, 0);
  EXPECT_NE(beyond.message.find("cuts no surface triangle"), std::string::npos);

  const double h = 10.0 / 34.0;
  const Eigen::Quaterniond flip = about(Eigen::Vector3d::UnitX(), M_PI);  // k = -z
  struct Case {
    double z;
    Eigen::Quaterniond rotation;
    bool grabs;
  };
  // On a cap's plane, the band next to the cap is grabbed when k points out of the body across
  // the cap, nothing when it points in: the plane counts as moved slightly along -k.
  for (const Case& cs : {Case{10, Eigen::Quaterniond::Identity(), true}, Case{10, flip, false},
                         Case{0, Eigen::Quaterniond::Identity(), false}, Case{0, flip, true}}) {
    const HandSelection sel = expectMatchesBruteForce(mesh, x, makeFrame({0, 0, cs.z}, cs.rotation),
                                                      "cap at z = " + std::to_string(cs.z));
    if (!cs.grabs) {
      EXPECT_EQ(sel.status, HandSelectionStatus::kNoTriangleCut);
      continue;
    }
    ASSERT_EQ(sel.status, HandSelectionStatus::kGrabbed);
    // The rim and the lateral band next to it; not the cap's inside. The same as the plane moved
    // 1e-7 m along -k.
    int rim = 0;
    for (int n : sel.nodes) {
      EXPECT_GE(x.segment<2>(3 * n).norm(), kInradius - 1e-9);
      EXPECT_LT(std::abs(x(3 * n + 2) - cs.z), 2 * h + 1e-9);
      rim += std::abs(x(3 * n + 2) - cs.z) < 1e-9;
    }
    EXPECT_GE(rim, 11);
    const Frame shifted = makeFrame(
        Eigen::Vector3d(0, 0, cs.z) - 1e-7 * (cs.rotation * Eigen::Vector3d::UnitZ()), cs.rotation);
    EXPECT_EQ(sel.triangles, selectGrabbedPatch(mesh, x, shifted).triangles);
  }
}

// ---- a U: two legs joined by a bottom bar

TetMesh uShape() {
  // [0,3] x [0,1] x [0,3] in 0.5 m cells; drop the notch x in [1,2], z in [1,3].
  const TetMesh box = makeBoxTetMesh({0, 0, 0}, {3, 1, 3}, 6, 2, 6).value();
  std::vector<Tet> kept;
  for (const Tet& tet : box.tets()) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int n : tet)
      centroid += box.restPositions()[static_cast<size_t>(n)] / 4;
    if (centroid.x() > 1 && centroid.x() < 2 && centroid.z() > 1) continue;
    kept.push_back(tet);
  }
  // Renumber the nodes still in use.
  std::vector<int> index(static_cast<size_t>(box.nodeCount()), -1);
  std::vector<Eigen::Vector3d> positions;
  for (Tet& tet : kept) {
    for (int& n : tet) {
      if (index[static_cast<size_t>(n)] < 0) {
        index[static_cast<size_t>(n)] = static_cast<int>(positions.size());
        positions.push_back(box.restPositions()[static_cast<size_t>(n)]);
      }
      n = index[static_cast<size_t>(n)];
    }
  }
  return TetMesh(std::move(positions), std::move(kept));
}

TEST(HandPlane, UShapeGrabsOnlyTheLegTheRayHits) {
  const TetMesh mesh = uShape();
  const Eigen::VectorXd x = restPositionsOf(mesh);
  const Eigen::Quaterniond half_turn = about(Eigen::Vector3d::UnitZ(), M_PI);  // i = -x
  struct Case {
    Eigen::Vector3d origin;
    Eigen::Quaterniond rotation;
    bool left;  // which leg should be grabbed
  };
  for (double z : {2.25, 2.0}) {  // between node layers and exactly on one
    for (const Case& cs :
         {Case{{0.5, 0.5, z}, Eigen::Quaterniond::Identity(), true},   // inside the left leg, +x
          Case{{0.5, 0.5, z}, half_turn, true},                        // inside the left leg, -x
          Case{{1.5, 0.5, z}, Eigen::Quaterniond::Identity(), false},  // in the notch, +x
          Case{{1.5, 0.5, z}, half_turn, true},                        // in the notch, -x
          Case{{2.5, 0.5, z}, half_turn, false}}) {                    // inside the right leg
      const std::string label = "O = (" + std::to_string(cs.origin.x()) + ", .., " +
                                std::to_string(z) + "), " + (cs.left ? "left" : "right");
      const HandSelection sel =
          expectMatchesBruteForce(mesh, x, makeFrame(cs.origin, cs.rotation), label);
      ASSERT_EQ(sel.status, HandSelectionStatus::kGrabbed) << label;
      // The plane cuts both legs; only one leg's ring is grabbed.
      EXPECT_EQ(static_cast<int>(sel.triangles.size()) * 2, sel.cut_triangle_count) << label;
      for (int n : sel.nodes) {
        if (cs.left) {
          EXPECT_LE(x(3 * n), 1 + 1e-12) << label;
        } else {
          EXPECT_GE(x(3 * n), 2 - 1e-12) << label;
        }
      }
    }
  }
}

// ---- a Hand on a body in a world

struct TwistRig {
  FemWorld world;
  FemBody* body = nullptr;
  std::vector<int> base;

  explicit TwistRig(const Material& material) : world(settings()) {
    body = world.addBody("cyl", cylinder(), material).value();
    for (int n = 0; n < cylinder().nodeCount(); ++n) {
      if (cylinder().restPositions()[static_cast<size_t>(n)].z() < 1e-9) base.push_back(n);
    }
    body->carryNodes(
        "base", base, [](double) { return Frame{}; }, world.time());
  }
  static WorldSettings settings() {
    WorldSettings s;
    s.gravity.setZero();
    return s;
  }
};

Material dampedMaterial() {
  Material m;
  m.youngs_modulus = 1e6;
  m.mass_damping = 5;  // 1/s: the released body settles within the test's 2 s
  return m;
}

TEST(Hand, CarriesThePatchRigidlyFreesItAndTheBodyReturnsToRest) {
  TwistRig rig(dampedMaterial());
  FemBody& body = *rig.body;
  const TetMesh& mesh = body.model().mesh();
  Hand hand(body);
  EXPECT_FALSE(hand.grabbed());
  EXPECT_TRUE(hand.grabbedNodes().empty());

  // Grab on the top cap's plane (k = +z points out of the body): the rim and the ring below it.
  const Eigen::Vector3d O(0, 0, 10);
  const Result<int> n = hand.grab(makeFrame(O), rig.world.time());
  ASSERT_TRUE(n.ok()) << n.error().message;
  EXPECT_GE(n.value(), 22);
  for (int node : hand.grabbedNodes()) {
    EXPECT_GE(mesh.restPositions()[static_cast<size_t>(node)].z(), 10 - 2 * 10.0 / 34);
    EXPECT_GE(mesh.restPositions()[static_cast<size_t>(node)].head<2>().norm(), kInradius - 1e-9);
  }
  ASSERT_TRUE(hand.grabbed());
  EXPECT_EQ(hand.grabbedNodes(), hand.selection().nodes);
  const int group = hand.group();
  EXPECT_EQ(body.groups()[static_cast<size_t>(group)]->nodes(), hand.grabbedNodes());
  std::set<int> grabbed(hand.grabbedNodes().begin(), hand.grabbedNodes().end());

  // Twist by 0.3 rad about +z over 20 steps. p_hat = R0^T (p0 - O) with R0 = I.
  const int steps = 20;
  const double total = 0.3;
  for (int s = 1; s <= steps; ++s) {
    const Frame target = makeFrame(O, about(Eigen::Vector3d::UnitZ(), total * s / steps));
    EXPECT_TRUE(hand.moveTo(target).ok());
    const WorldStepReport r = rig.world.step();
    ASSERT_TRUE(r.ok) << r.message;
    int carried = 0;
    for (int node = 0; node < mesh.nodeCount(); ++node) {
      const Eigen::Vector3d rest = mesh.restPositions()[static_cast<size_t>(node)];
      const Eigen::Vector3d carried_target = target.toWorld(rest - O);
      const double gap = (body.state().position(node) - carried_target).norm();
      if (grabbed.count(node)) {
        EXPECT_LT(gap, 1e-12) << "grabbed node " << node << ", step " << s;
        ++carried;
      } else if ((carried_target - rest).norm() > 1e-6) {
        // A free node that the rigid motion would move is not on its carried target.
        EXPECT_GT(gap, 1e-9) << "free node " << node << ", step " << s;
      }
    }
    EXPECT_EQ(carried, n.value());
  }
  const Wrench twisted = hand.wrench();
  EXPECT_LT(twisted.torque.z(), 0);

  hand.release();
  EXPECT_FALSE(hand.grabbed());
  EXPECT_TRUE(hand.grabbedNodes().empty());
  EXPECT_EQ(hand.wrench().torque, Eigen::Vector3d::Zero());
  double energy_at_release = -1, energy_now = 0;
  for (int s = 0; s < 200; ++s) {
    const WorldStepReport r = rig.world.step();
    ASSERT_TRUE(r.ok) << r.message;
    if (s == 0) energy_at_release = body.lastReport().elastic_energy;  // at the start of the step
    energy_now = body.lastReport().elastic_energy;
  }
  ASSERT_GT(energy_at_release, 0);
  EXPECT_LT(energy_now, 0.01 * energy_at_release);
  // The formerly grabbed nodes moved back toward their rest positions.
  for (int node : grabbed) {
    const Eigen::Vector3d rest = mesh.restPositions()[static_cast<size_t>(node)];
    EXPECT_LT((body.state().position(node) - rest).norm(), 0.02) << node;
  }
  const Wrench after = hand.wrench();
  EXPECT_EQ(after.force, Eigen::Vector3d::Zero());
  EXPECT_EQ(after.torque, Eigen::Vector3d::Zero());
  // The body keeps the released group's index, empty, with zero wrench.
  EXPECT_TRUE(body.groups()[static_cast<size_t>(group)]->nodes().empty());
  EXPECT_EQ(body.groupWrench(group, O).torque, Eigen::Vector3d::Zero());
}

TEST(Hand, WrenchOpposesTheTwist) {
  for (double sign : {1.0, -1.0}) {
    TwistRig rig(Material{});
    Hand hand(*rig.body);
    const Eigen::Vector3d O(0, 0, 9.99);
    ASSERT_TRUE(hand.grab(makeFrame(O), rig.world.time()).ok());
    EXPECT_EQ(hand.wrench().torque, Eigen::Vector3d::Zero());  // no step yet
    for (int s = 1; s <= 10; ++s) {
      EXPECT_TRUE(hand.moveTo(makeFrame(O, about(Eigen::Vector3d::UnitZ(), sign * 0.02 * s))).ok());
      ASSERT_TRUE(rig.world.step().ok);
    }
    const Wrench w = hand.wrench();
    EXPECT_LT(sign * w.torque.z(), 0) << "sign " << sign;
    // A pure twist about the axis: the torque is mostly about z.
    EXPECT_LT(std::abs(w.torque.x()) + std::abs(w.torque.y()), 0.2 * std::abs(w.torque.z()));
  }
}

TEST(Hand, FailedGrabIsAnErrorAndTheHandGrabsAgainElsewhere) {
  TwistRig rig(Material{});
  FemBody& body = *rig.body;
  Hand hand(body, "left");
  const Result<int> missed = hand.grab(makeFrame({0, 0, 20}), rig.world.time());
  ASSERT_FALSE(missed.ok());
  EXPECT_NE(missed.error().message.find("hand 'left' on body 'cyl'"), std::string::npos)
      << missed.error().message;
  EXPECT_NE(missed.error().message.find("cuts no surface triangle"), std::string::npos);
  EXPECT_FALSE(hand.grabbed());
  const Result<int> away = hand.grab(makeFrame({3, 0, 5}), rig.world.time());
  ASSERT_FALSE(away.ok());
  EXPECT_NE(away.error().message.find("ray"), std::string::npos) << away.error().message;

  // Grab at z = 9.99, pull up by 1 cm, let go, grab at z = 5 and push sideways.
  ASSERT_TRUE(hand.grab(makeFrame({0, 0, 9.99}), rig.world.time()).ok());
  const std::vector<int> first = hand.grabbedNodes();
  const int first_group = hand.group();
  for (int s = 1; s <= 5; ++s) {
    EXPECT_TRUE(hand.moveTo(makeFrame({0, 0, 9.99 + 0.002 * s})).ok());
    ASSERT_TRUE(rig.world.step().ok);
  }
  for (int node : first) {
    EXPECT_NEAR(body.state().position(node).z(),
                body.model().mesh().restPositions()[static_cast<size_t>(node)].z() + 0.01, 1e-12);
  }
  hand.release();
  EXPECT_TRUE(body.groups()[static_cast<size_t>(first_group)]->nodes().empty());

  const Frame mid = makeFrame({0, 0, 5});
  const Result<int> again = hand.grab(mid, rig.world.time());
  ASSERT_TRUE(again.ok()) << again.error().message;
  EXPECT_NE(hand.group(), first_group);
  // Selected at the current positions, which the pull moved a little: a ring near z = 5.
  EXPECT_GE(again.value(), 22);
  for (int node : hand.grabbedNodes())
    EXPECT_LT(std::abs(body.state().position(node).z() - 5), 2 * 10.0 / 34 + 0.01);
  std::vector<Eigen::Vector3d> local;
  for (int node : hand.grabbedNodes())
    local.push_back(body.state().position(node) - mid.origin);
  for (int s = 1; s <= 5; ++s) {
    EXPECT_TRUE(hand.moveTo(makeFrame(mid.origin + Eigen::Vector3d(0.004 * s, 0, 0))).ok());
    ASSERT_TRUE(rig.world.step().ok);
  }
  for (size_t k = 0; k < local.size(); ++k) {
    const int node = hand.grabbedNodes()[k];
    EXPECT_LT((body.state().position(node) - (mid.origin + Eigen::Vector3d(0.02, 0, 0) + local[k]))
                  .norm(),
              1e-12);
  }
  // The first ring is free again: it no longer sits on its last carried target.
  double moved = 0;
  for (int node : first) {
    moved = std::max(
        moved,
        std::abs(body.state().position(node).z() -
                 (body.model().mesh().restPositions()[static_cast<size_t>(node)].z() + 0.01)));
  }
  EXPECT_GT(moved, 1e-6);
}

TEST(Hand, TwoHandsAndFixedNodesOnOneBodyHoldTheirOwnPatchesInEquilibrium) {
  TwistRig rig(dampedMaterial());
  FemBody& body = *rig.body;
  Hand middle(body, "middle"), end(body, "end");
  const Eigen::Vector3d a(0, 0, 5), b(0, 0, 9.9);
  ASSERT_TRUE(middle.grab(makeFrame(a), rig.world.time()).ok());
  ASSERT_TRUE(end.grab(makeFrame(b), rig.world.time()).ok());
  std::set<int> shared;
  std::set_intersection(middle.grabbedNodes().begin(), middle.grabbedNodes().end(),
                        end.grabbedNodes().begin(), end.grabbedNodes().end(),
                        std::inserter(shared, shared.begin()));
  EXPECT_TRUE(shared.empty());
  std::vector<Eigen::Vector3d> rest;
  for (int n = 0; n < body.model().nodeCount(); ++n)
    rest.push_back(body.state().position(n));

  // The middle ring turns 0.1 rad one way, the end ring 0.2 rad the other, then both hold.
  const Frame turned_a = makeFrame(a, about(Eigen::Vector3d::UnitZ(), 0.1));
  const Frame turned_b = makeFrame(b, about(Eigen::Vector3d::UnitZ(), -0.2));
  for (int s = 1; s <= 300; ++s) {
    const double f = std::min(1.0, s / 20.0);
    EXPECT_TRUE(middle.moveTo(makeFrame(a, about(Eigen::Vector3d::UnitZ(), 0.1 * f))).ok());
    EXPECT_TRUE(end.moveTo(makeFrame(b, about(Eigen::Vector3d::UnitZ(), -0.2 * f))).ok());
    const WorldStepReport r = rig.world.step();
    ASSERT_TRUE(r.ok) << r.message;
  }
  for (int node : middle.grabbedNodes()) {
    EXPECT_LT((body.state().position(node) - turned_a.toWorld(rest[size_t(node)] - a)).norm(),
              1e-12);
  }
  for (int node : end.grabbedNodes()) {
    EXPECT_LT((body.state().position(node) - turned_b.toWorld(rest[size_t(node)] - b)).norm(),
              1e-12);
  }
  // At rest the three supports balance: the torques about the axis sum to zero.
  const double t_middle = middle.wrench().torque.z();
  const double t_end = end.wrench().torque.z();
  const double t_base = body.groupWrench(0, Eigen::Vector3d::Zero()).torque.z();
  EXPECT_LT(t_middle, 0);  // the body resists the middle's +z turn
  EXPECT_GT(t_end, 0);
  EXPECT_LT(std::abs(t_middle + t_end + t_base), 0.01 * std::abs(t_end));
  // Between the hands the twist is -0.3 rad over 4.9 m, below them 0.1 rad over 5 m: the end
  // hand carries 0.3 / 4.9 against 0.1 / 5 of the base's rate, torque in proportion (+-10 %:
  // the rings' grabbed bands shorten the free lengths a little).
  EXPECT_GT(t_base, 0);  // the body drags the base along the middle's turn
  EXPECT_NEAR(t_end / t_base, (0.3 / 4.9) / (0.1 / 5), 0.1 * (0.3 / 4.9) / (0.1 / 5));
}

// A frame that is not a pose (the zero quaternion of Frame{origin, {}}, a scaled one, a NaN
// origin) is refused by grab and moveTo with a message naming the hand, and changes nothing: the
// goal stays where it was. A body's velocity that is not finite is refused likewise.
TEST(Hand, FramesThatAreNotPosesAndNonFiniteVelocitiesAreRefused) {
  TwistRig rig(Material{});
  Hand hand(*rig.body, "left");
  const Eigen::Vector3d O(0, 0, 9.99);
  Frame zero{O, Eigen::Quaterniond(0, 0, 0, 0)};
  Result<int> grabbed = hand.grab(zero, rig.world.time());
  ASSERT_FALSE(grabbed.ok());
  EXPECT_NE(grabbed.error().message.find("hand 'left' on body"), std::string::npos)
      << grabbed.error().message;
  EXPECT_NE(grabbed.error().message.find("not a unit quaternion"), std::string::npos)
      << grabbed.error().message;
  EXPECT_FALSE(hand.grabbed());

  ASSERT_TRUE(hand.grab(makeFrame(O), rig.world.time()).ok());
  const Frame goal = hand.goal();
  const Frame scaled{O, Eigen::Quaterniond(2, 0, 0, 0)};
  const Frame lost{Eigen::Vector3d(std::nan(""), 0, 0), Eigen::Quaterniond::Identity()};
  for (const Frame& bad : {zero, scaled, lost}) {
    const Status moved = hand.moveTo(bad);
    ASSERT_FALSE(moved.ok());
    EXPECT_NE(moved.error().message.find("hand 'left'"), std::string::npos)
        << moved.error().message;
    EXPECT_EQ(hand.goal().origin, goal.origin);
    EXPECT_EQ(hand.goal().rotation.coeffs(), goal.rotation.coeffs());
  }
  const Eigen::VectorXd before = rig.body->state().velocities;
  const Status set = rig.body->setVelocity(Eigen::Vector3d(0, std::nan(""), 0));
  ASSERT_FALSE(set.ok());
  EXPECT_NE(set.error().message.find("not finite"), std::string::npos) << set.error().message;
  EXPECT_FALSE(
      rig.body
          ->setRigidVelocity(Eigen::Vector3d::Zero(),
                             Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0, 0))
          .ok());
  EXPECT_EQ((rig.body->state().velocities - before).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace torsion
