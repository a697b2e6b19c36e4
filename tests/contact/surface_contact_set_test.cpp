// SurfaceContactSet's memory from one step to the next (surface_contact_set.h): a contact that
// pushed at the end of a step starts the next with its impulse, projected onto its new friction
// cone; one that did not push, or is found again under another key, starts inactive.
#include "torsion/contact/surface_contact_set.h"

#include <gtest/gtest.h>

namespace torsion {
namespace {

SurfaceContact nodeOverTriangle(int node, int triangle, double friction) {
  SurfaceContact c;
  c.nodes = {node, 1, 2, 3};
  c.beta = {1.0, -1.0 / 3, -1.0 / 3, -1.0 / 3};
  c.triangle = triangle;
  c.normal = Eigen::Vector3d::UnitZ();
  c.friction = friction;
  return c;
}

TEST(SurfaceContactSet, APushingContactStartsTheNextStepWithItsImpulseInsideItsNewCone) {
  SurfaceContactSet set;
  set.beginStep();
  set.add(nodeOverTriangle(0, 7, 0.5));
  set.add(nodeOverTriangle(4, 7, 0.5));
  // The solve's answer: node 0 pushed 2 N s with 0.4 N s of friction, node 4 let go.
  set.contacts()[0].multiplier = Eigen::Vector3d(0.4, 0, 2);
  set.contacts()[0].state = SurfaceContact::State::kStick;
  const SurfaceContactSet::WarmStarts warm = set.warmStarts();
  ASSERT_EQ(warm.size(), 1u);

  set.beginStep();
  EXPECT_TRUE(set.wasActive(0, 7));
  EXPECT_FALSE(set.wasActive(4, 7));
  EXPECT_FALSE(set.wasActive(0, 8));
  // Found again with a lower friction coefficient: the 0.4 N s of friction exceed 0.1 x 2 N s,
  // so it starts sliding at the cone's edge; the normal impulse is kept.
  set.add(nodeOverTriangle(0, 7, 0.1));
  set.add(nodeOverTriangle(4, 7, 0.5));
  const SurfaceContact& kept = set.contacts()[0];
  EXPECT_EQ(kept.state, SurfaceContact::State::kSlide);
  EXPECT_DOUBLE_EQ(kept.multiplier.z(), 2.0);
  EXPECT_NEAR(kept.multiplier.x(), 0.2, 1e-15);
  EXPECT_EQ(set.contacts()[1].state, SurfaceContact::State::kInactive);
  EXPECT_EQ(set.contacts()[1].multiplier, Eigen::Vector3d::Zero());
}

TEST(SurfaceContactSet, RestoredWarmStartsSurviveTheNextBeginStep) {
  SurfaceContactSet set;
  set.setWarmStarts({{(std::uint64_t{3} << 32) | 9, Eigen::Vector3d(0, 0, 1)}});
  set.beginStep();
  EXPECT_TRUE(set.wasActive(3, 9));
  set.add(nodeOverTriangle(3, 9, 0.3));
  EXPECT_EQ(set.contacts()[0].state, SurfaceContact::State::kStick);
}

}  // namespace
}  // namespace torsion
