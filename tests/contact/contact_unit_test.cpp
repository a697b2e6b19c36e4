// Contact narrow phase and bookkeeping: signed distances against closed forms (and libccd when
// available), the ball mesh, held nodes never moved by a contact.

#include <gtest/gtest.h>

#include "contact_fixtures.h"
#include "torsion/contact/shape_distance.h"

namespace torsion::test {
namespace {

TEST(ShapeDistance, Sphere) {
  btSphereShape s(0.5);
  auto d = signedDistance(s, at({1, 0, 0}), {1, 0, 2}, 0);
  ASSERT_TRUE(d.has_value());
  EXPECT_NEAR(d->distance, 1.5, 1e-12);
  EXPECT_NEAR(d->normal.z(), 1.0, 1e-12);
}

}  // namespace
}  // namespace torsion::test
