#include "render_fixture.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>

#include "offscreen.h"
#include "scene_parser.h"
#include "scene_runner.h"

namespace torsion::render::test {

namespace fs = std::filesystem;

namespace {

OffscreenRenderer& offscreen() {
  static std::unique_ptr<OffscreenRenderer> r = [] {
    auto made = OffscreenRenderer::create(kWidth, kHeight, 2);
    if (!made) {
      ADD_FAILURE() << made.error().message;
      return std::unique_ptr<OffscreenRenderer>();
    }
    return std::move(made).value();
  }();
  return *r;
}

}  // namespace

RenderOptions compareOptions() {
  RenderOptions o;
  o.mesh_lines = false;
  return o;
}

Rendered loadAndCapture(const std::string& name, int steps) {
  Result<scene::SceneSpec> spec =
      scene::loadScene(std::string(TORSION_TEST_DATA) + "/render/" + name + ".json");
  if (!spec.ok()) {
    ADD_FAILURE() << spec.error().message;
    return {};
  }
  auto built = scene::buildScene(std::move(spec).value(), scene::BuildOptions{1});
  if (!built.ok()) {
    ADD_FAILURE() << built.error().message;
    return {};
  }
  scene::BuiltScene& s = *built.value();
  for (int k = 0; k < steps; ++k) {
    EXPECT_TRUE(scene::driveHands(s).ok());
    EXPECT_TRUE(s.world->step().ok);
  }
  Rendered r;
  r.frame = captureFrame(s);
  r.camera = offscreen().fitCamera(r.frame, compareOptions());
  return r;
}

Image draw(const Rendered& scene, const FrameData& frame) {
  return offscreen().render(frame, scene.camera, compareOptions());
}

std::string referencePath(const std::string& name) {
  return std::string(TORSION_TEST_DATA) + "/render/" + name + ".png";
}

Image reference(const std::string& name) {
  Result<Image> ref = readPng(referencePath(name));
  if (!ref) {
    ADD_FAILURE() << ref.error().message
                  << " (make it with TORSION_UPDATE_REFERENCES=1, see tests/data/README.md)";
    return {};
  }
  return std::move(ref).value();
}

ImageDifference against(const Image& reference, const Image& picture) {
  Result<ImageDifference> d = compareImages(reference, picture, kPixelThreshold);
  EXPECT_TRUE(d.ok()) << (d.ok() ? "" : d.error().message);
  return d.ok() ? d.value() : ImageDifference{255, 1, kPixelThreshold};
}

bool passes(const ImageDifference& d) {
  return d.mean_abs <= kMaxMeanAbs && d.differing_fraction <= kMaxDifferingFraction;
}

void expectMatchesReference(const std::string& name, const Rendered& scene) {
  const Image picture = draw(scene, scene.frame);
  const fs::path actual = fs::current_path() / ("render_actual_" + name + ".png");
  ASSERT_TRUE(writePng(picture, actual.string()).ok());
  if (std::getenv("TORSION_UPDATE_REFERENCES")) {
    ASSERT_TRUE(writePng(picture, referencePath(name)).ok());
    GTEST_SKIP() << "reference written to " << referencePath(name) << ": look at it";
  }
  const ImageDifference d = against(reference(name), picture);
  EXPECT_TRUE(passes(d)) << "mean |diff| " << d.mean_abs << ", differing pixels "
                         << d.differing_fraction << "; this run's picture: " << actual;
}

void expectCaught(const std::string& name, const Rendered& scene, const FrameData& perturbed,
                  const char* what) {
  const ImageDifference d = against(reference(name), draw(scene, perturbed));
  EXPECT_FALSE(passes(d)) << what << ": mean |diff| " << d.mean_abs << ", differing pixels "
                          << d.differing_fraction;
  EXPECT_GT(d.differing_fraction, 2 * kMaxDifferingFraction) << what;
  std::cout << what << ": mean |diff| " << d.mean_abs << ", differing " << d.differing_fraction
            << "\n";
}

}  // namespace torsion::render::test
