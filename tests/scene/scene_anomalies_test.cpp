// The scene runner's anomaly watch (scene_anomalies.h) on the demo scenes that behave: a drop
// that bounces, a plate that presses a block, the first seconds of the cylinder twist. None may
// raise an anomaly; summary.json lists an empty "anomalies" array and the run is not stopped.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "demo_scenes.h"
#include "scene_runner.h"

namespace torsion::scene {
namespace {

nlohmann::json runAndReadSummary(const std::string& name, int steps) {
  std::unique_ptr<BuiltScene> built = buildDemoScene(name);
  if (!built) return {};
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() /
      ("torsion_scene_anomalies_test_" + name + "_" + std::to_string(::getpid()));
  RunOptions options;
  options.output_directory = out.string();
  options.steps = steps;
  options.stop_on_anomaly = true;
  Result<RunOutcome> outcome = runScene(*built, options);
  if (!outcome.ok()) {
    ADD_FAILURE() << outcome.error().message;
    return {};
  }
  EXPECT_TRUE(outcome.value().stable) << outcome.value().failure;
  EXPECT_EQ(outcome.value().stopped_on_anomaly, "");
  EXPECT_EQ(outcome.value().steps_done, steps);
  nlohmann::json summary;
  std::ifstream(out / "summary.json") >> summary;
  std::filesystem::remove_all(out);
  return summary;
}

void expectNoAnomalies(const nlohmann::json& summary) {
  ASSERT_TRUE(summary.contains("anomalies"));
  EXPECT_TRUE(summary["anomalies"].empty()) << summary["anomalies"].dump(1);
  EXPECT_EQ(summary["stopped_on_anomaly"], false);
}

TEST(SceneAnomalies, ADropThatBouncesRaisesNone) {
  expectNoAnomalies(runAndReadSummary("drop", 150));
}

TEST(SceneAnomalies, APlatePressingABlockRaisesNone) {
  expectNoAnomalies(runAndReadSummary("press", 250));
}

TEST(SceneAnomalies, TheFirstSecondsOfTheCylinderTwistRaiseNone) {
  expectNoAnomalies(runAndReadSummary("twist_cylinder_2430", 300));
}

}  // namespace
}  // namespace torsion::scene
