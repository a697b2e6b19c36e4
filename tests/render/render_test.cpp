// Render tests (label "render"): OSMesa draws a known scene and the picture is compared with a
// stored reference by a tolerant metric; perturbing the drawn data (a body missing, the colour
// map reversed, the normals flipped, a rigid body missing) must fail the same comparison.
//
// Regenerate the reference after an intended change of the pictures (then look at it):
//   TORSION_UPDATE_REFERENCES=1 build/tests/render/torsion_render_tests

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "render_fixture.h"

namespace torsion::render {
namespace {

namespace fs = std::filesystem;
using namespace test;

// The twist_bar scene after 40 steps (0.8 rad of twist), captured as a FrameData.
const Rendered& twistBar() {
  static const Rendered rendered = loadAndCapture("twist_bar", 40);
  return rendered;
}

Image draw(const FrameData& frame) {
  return test::draw(twistBar(), frame);
}

void expectCaught(const FrameData& perturbed, const char* what) {
  test::expectCaught("twist_bar", twistBar(), perturbed, what);
}

TEST(Render, TwistBarMatchesReference) {
  expectMatchesReference("twist_bar", twistBar());
}

TEST(Render, SameFrameDrawsTheSamePicture) {
  const Image a = draw(twistBar().frame), b = draw(twistBar().frame);
  EXPECT_EQ(a.rgb, b.rgb);
}

TEST(Render, MissingBodyIsCaught) {
  FrameData f = twistBar().frame;
  f.bodies.clear();
  expectCaught(f, "no FEM body");
}

TEST(Render, MissingRigidBodyIsCaught) {
  FrameData f = twistBar().frame;
  f.rigids.erase(
      std::remove_if(f.rigids.begin(), f.rigids.end(),
                     [](const RigidDrawData& r) { return r.shape == RigidDrawData::Shape::kBox; }),
      f.rigids.end());
  expectCaught(f, "no crate");
}

TEST(Render, ReversedColourMapIsCaught) {
  FrameData f = twistBar().frame;
  for (BodyDrawData& b : f.bodies) {
    for (float& s : b.stress)
      s = static_cast<float>(f.stress_max) - s;
  }
  expectCaught(f, "colour map reversed");
}

TEST(Render, FlippedNormalsAreCaught) {
  FrameData f = twistBar().frame;
  for (BodyDrawData& b : f.bodies) {
    for (Eigen::Vector3f& n : b.normals)
      n = -n;
  }
  expectCaught(f, "normals flipped");
}

TEST(Render, GrabbedNodesAreShown) {
  // The hand holds its patch: orange pixels must be in the picture.
  ASSERT_FALSE(twistBar().frame.bodies.empty());
  EXPECT_GT(twistBar().frame.bodies[0].grabbed_nodes.size(), 10u);
  const Image picture = draw(twistBar().frame);
  int orange = 0;
  for (int y = 0; y < picture.height; ++y) {
    for (int x = 0; x < picture.width; ++x) {
      const std::uint8_t* p = picture.pixel(x, y);
      if (p[0] > 200 && p[1] > 90 && p[1] < 160 && p[2] < 60) ++orange;
    }
  }
  EXPECT_GT(orange, 30);
}

TEST(Image, PngRoundTrip) {
  Image image;
  image.width = 7;
  image.height = 5;
  for (int i = 0; i < 7 * 5 * 3; ++i)
    image.rgb.push_back(static_cast<std::uint8_t>(i * 7));
  const std::string path = (fs::temp_directory_path() / "torsion_png_round_trip.png").string();
  ASSERT_TRUE(writePng(image, path).ok());
  Result<Image> back = readPng(path);
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back.value().width, 7);
  EXPECT_EQ(back.value().rgb, image.rgb);
  fs::remove(path);
  EXPECT_FALSE(readPng(path).ok());
}

TEST(Image, CompareCountsDifferingPixels) {
  Image a;
  a.width = 10;
  a.height = 10;
  a.rgb.assign(300, 100);
  Image b = a;
  b.pixel(3, 4)[1] = 200;  // one pixel, one channel, 100 levels
  const ImageDifference d = compareImages(a, b, 24).value();
  EXPECT_DOUBLE_EQ(d.differing_fraction, 0.01);
  EXPECT_DOUBLE_EQ(d.mean_abs, 100.0 / 300);
  Image c = a;
  c.width = 5;
  EXPECT_FALSE(compareImages(a, c, 24).ok());
}

TEST(Stress, NiceCeilingAndColourMap) {
  EXPECT_DOUBLE_EQ(niceCeiling(3.2e4), 5e4);
  EXPECT_DOUBLE_EQ(niceCeiling(2e3), 2e3);
  EXPECT_DOUBLE_EQ(niceCeiling(0), 1);
  // Lightness rises along the map.
  double last = -1;
  for (int i = 0; i <= 10; ++i) {
    const Eigen::Vector3d c = stressColour(i / 10.0);
    const double luma = 0.3 * c.x() + 0.59 * c.y() + 0.11 * c.z();
    EXPECT_GT(luma, last);
    last = luma;
  }
}

}  // namespace
}  // namespace torsion::render
