// Bullet's deformable demos re-created as scene files (demos/scenes/bullet_*.json, listed in
// docs/scene-format.md): each runs to its end as `torsion run` runs it (buildScene, then
// driveHands and FemWorld::step per step) and the demo's defining outcome holds. Label "physics".
// bullet_deformable_rigid is left to bench_bullet_demos, which checks its outcome: a 1536-tet
// sheet draped over rigid bodies, about 700 contact rows a solve, 480 steps at about 44 steps/s
// in Release (docs/performance-contact.md), 11 s of a CI budget already spent; the regression
// suite steps its first 50.

#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>
#include <functional>
#include <limits>

#include "demo_scenes.h"

namespace torsion::scene {
namespace {

// Runs the scene's steps, calling `each` after every step; fails on an unstable step.
void run(BuiltScene& s, const std::function<void(int step)>& each = {}) {
  for (int k = 0; k < s.spec.steps; ++k) {
    ASSERT_TRUE(driveHands(s));
    const WorldStepReport r = s.world->step();
    ASSERT_TRUE(r.ok) << s.spec.name << " step " << k << ": " << r.message;
    if (each) each(k + 1);
  }
}

const FemBody& soft(const BuiltScene& s) {
  return *s.world->bodies().front();
}

Eigen::Vector3d centreOfMass(const FemBody& b) {
  const std::vector<double>& m = b.model().nodeMasses();
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int i = 0; i < b.model().nodeCount(); ++i)
    c += m[static_cast<size_t>(i)] * b.state().position(i);
  return c / b.model().totalMass();
}

double lowestZ(const FemBody& b) {
  double z = std::numeric_limits<double>::infinity();
  for (int i = 0; i < b.model().nodeCount(); ++i)
    z = std::min(z, b.state().position(i).z());
  return z;
}

double heightOf(const FemBody& b) {
  double top = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < b.model().nodeCount(); ++i)
    top = std::max(top, b.state().position(i).z());
  return top - lowestZ(b);
}

// Smallest signed volume over the tets divided by its rest volume: <= 0 means an inverted tet.
double smallestVolumeRatio(const FemBody& b) {
  const TetMesh& mesh = b.model().mesh();
  double smallest = std::numeric_limits<double>::infinity();
  for (int t = 0; t < mesh.tetCount(); ++t) {
    const Tet& tet = mesh.tets()[static_cast<size_t>(t)];
    const Eigen::Vector3d a = b.state().position(tet[0]);
    const double v =
        (b.state().position(tet[1]) - a)
            .dot((b.state().position(tet[2]) - a).cross(b.state().position(tet[3]) - a)) /
        6;
    smallest = std::min(smallest, v / mesh.restVolume(t));
  }
  return smallest;
}

// RMS distance of the nodes from the rest shape moved rigidly onto them (Kabsch's best fit).
double distanceFromRestShape(const FemBody& b) {
  const std::vector<Eigen::Vector3d>& rest = b.model().mesh().restPositions();
  const int n = b.model().nodeCount();
  Eigen::Vector3d rc = Eigen::Vector3d::Zero(), xc = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    rc += rest[static_cast<size_t>(i)];
    xc += b.state().position(i);
  }
  rc /= n;
  xc /= n;
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i)
    h += (rest[static_cast<size_t>(i)] - rc) * (b.state().position(i) - xc).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
  const Eigen::Matrix3d rotation = svd.matrixV() * d * svd.matrixU().transpose();
  double sum = 0;
  for (int i = 0; i < n; ++i)
    sum +=
        (rotation * (rest[static_cast<size_t>(i)] - rc) + xc - b.state().position(i)).squaredNorm();
  return std::sqrt(sum / n);
}

Eigen::Vector3d rigidPosition(const BuiltScene& s, const std::string& name) {
  for (const SceneRigidBody& r : s.rigid_bodies)
    if (r.name == name) {
      const btVector3& p = r.body->getWorldTransform().getOrigin();
      return {p.x(), p.y(), p.z()};
    }
  ADD_FAILURE() << "no rigid body " << name;
  return Eigen::Vector3d::Zero();
}

TEST(BulletDemoScenes, PinchLiftsTheCubeOffTheGroundAndCarriesItBetweenTheFingers) {
  auto s = buildDemoScene("bullet_pinch");
  ASSERT_TRUE(s);
  double lowest_when_squeezed = 0;
  run(*s, [&](int step) {
    // The fingers close for 0.9 s (216 steps): by then the cube has dropped onto the ground.
    if (step == 216) lowest_when_squeezed = lowestZ(soft(*s));
  });
  EXPECT_LT(lowest_when_squeezed, 0.05) << "the cube should sit on the ground when squeezed";
  // Lifted 8 m and carried 5 m sideways: its bottom far above the ground, its centre of mass
  // between the fingers (their faces 3.4 m apart, 6 m tall).
  const Eigen::Vector3d mid =
      (rigidPosition(*s, "finger_left") + rigidPosition(*s, "finger_right")) / 2;
  const Eigen::Vector3d c = centreOfMass(soft(*s));
  EXPECT_GT(lowestZ(soft(*s)), 6.0);
  EXPECT_NEAR(c.y(), mid.y(), 0.5);
  EXPECT_NEAR(c.z(), mid.z(), 1.5);
  EXPECT_GT(smallestVolumeRatio(soft(*s)), 0.0);
}

TEST(BulletDemoScenes, CollideKnocksTheCubeAwayAndKeepsTheMomentum) {
  auto s = buildDemoScene("bullet_collide");
  ASSERT_TRUE(s);
  run(*s);
  // Box 0.5 kg at 30 m/s, cube 0.5 kg at rest, no gravity, no friction: the total momentum
  // stays 15 N s (contact impulses are equal and opposite), within the CG tolerance.
  const FemBody& cube = soft(*s);
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < cube.model().nodeCount(); ++i)
    p += cube.model().nodeMasses()[static_cast<size_t>(i)] * cube.state().velocity(i);
  const btRigidBody& box = *s->rigid_bodies.front().body;
  p.z() += 0.5 * static_cast<double>(box.getLinearVelocity().z());
  EXPECT_NEAR(p.z(), 15.0, 0.15);
  // The box stays below the cube: it hit it, did not pass through.
  EXPECT_LT(rigidPosition(*s, "box").z() + 2, lowestZ(cube) + 0.01);
  EXPECT_GT(centreOfMass(cube).z(), 7 + 5) << "the cube should have been knocked upwards";
}

TEST(BulletDemoScenes, VolumetricCubeHitByFallingBoxesComesToRestOnTheGroundInsideTheWalls) {
  auto s = buildDemoScene("bullet_volumetric_deformable");
  ASSERT_TRUE(s);
  run(*s);
  const FemBody& cube = soft(*s);
  EXPECT_GT(lowestZ(cube), -0.01) << "no node below the ground";
  for (int i = 0; i < cube.model().nodeCount(); ++i) {
    EXPECT_LT(std::abs(cube.state().position(i).x()), 4.01) << "node " << i << " in a wall";
    EXPECT_LT(std::abs(cube.state().position(i).y()), 4.01) << "node " << i << " in a wall";
  }
  EXPECT_NEAR(centreOfMass(cube).z(), 2.0, 0.5);
  EXPECT_GT(smallestVolumeRatio(cube), 0.0);
  // The 2 m boxes that fell on it: none below the ground (centre at least its half height up).
  for (const SceneRigidBody& r : s->rigid_bodies) {
    if (r.body->getInvMass() > 0) {
      EXPECT_GT(r.body->getWorldTransform().getOrigin().z(), 1 - 0.01) << r.name << " sank";
    }
  }
}

TEST(BulletDemoScenes, LargeDeformationCubeSqueezedToAThirdReturnsToItsRestShape) {
  auto s = buildDemoScene("bullet_large_deformation");
  ASSERT_TRUE(s);
  double squeezed_height = 0, smallest_ratio = std::numeric_limits<double>::infinity();
  run(*s, [&](int step) {
    if (step == 45) squeezed_height = heightOf(soft(*s));  // t = 0.75 s: plates at their closest
    smallest_ratio = std::min(smallest_ratio, smallestVolumeRatio(soft(*s)));
  });
  EXPECT_LT(squeezed_height, 1.3) << "the plates squeeze the 4 m cube to 1.2 m";
  EXPECT_GT(smallest_ratio, 0.0) << "an element inverted on the way";
  // Back at rest shape to 0.5 % of its edge (whatever rigid turn it took), where it was squeezed.
  EXPECT_LT(distanceFromRestShape(soft(*s)), 0.02);
  EXPECT_NEAR(centreOfMass(soft(*s)).z(), 8.0, 0.1);
}

}  // namespace
}  // namespace torsion::scene
