#pragma once
// The demo scenes (demos/scenes/NAME.json; TORSION_SCENES_DIR comes from CMake) loaded for the
// tests that run them as `torsion run` does: parsed, then built on one thread.

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "scene_builder.h"
#include "scene_parser.h"

namespace torsion::scene {

/// The demo scene `name` built, or nullptr with the parser's or builder's message recorded as a
/// (non-fatal) test failure.
inline std::unique_ptr<BuiltScene> buildDemoScene(const std::string& name) {
  Result<SceneSpec> spec = loadScene(std::string(TORSION_SCENES_DIR) + "/" + name + ".json");
  EXPECT_TRUE(spec) << (spec ? "" : spec.error().message);
  if (!spec) return nullptr;
  auto built = buildScene(std::move(spec).value(), BuildOptions{1});
  EXPECT_TRUE(built) << (built ? "" : built.error().message);
  return built ? std::move(built).value() : nullptr;
}

}  // namespace torsion::scene
