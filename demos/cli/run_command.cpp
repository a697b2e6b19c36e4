#include "run_command.h"

#include <iostream>
#include <memory>

#include "../scene/scene_parser.h"
#include "../scene/scene_runner.h"
#include "mesh_command.h"
#include "progress_bar.h"

namespace torsion::cli {

namespace {

struct RunArguments {
  std::string scene;
  std::string out = "results";
  int steps = -1;
  int threads = -1;
};

// Exit codes: 0 done and stable, 1 bad input or output error, 3 the simulation went unstable.
int run(const RunArguments& args) {
  Result<scene::SceneSpec> spec = scene::loadScene(args.scene);
  if (!spec) {
    std::cerr << "error: " << spec.error().message << "\n";
    return 1;
  }
  Result<std::unique_ptr<scene::BuiltScene>> built =
      scene::buildScene(std::move(spec).value(), args.threads);
  if (!built) {
    std::cerr << "error: " << built.error().message << "\n";
    return 1;
  }
  scene::BuiltScene& s = *built.value();
  for (const std::string& w : s.warnings)
    std::cerr << "warning: " << w << "\n";
  for (const auto& body : s.world->bodies()) {
    std::cerr << "body '" << body->name() << "': " << body->model().nodeCount() << " nodes, "
              << body->model().tetCount() << " tets\n";
  }

  ProgressBar bar(s.spec.name);
  scene::RunOptions options;
  options.output_directory = args.out;
  options.steps = args.steps;
  options.progress = [&bar](int done, int total, double rate) { bar.update(done, total, rate); };
  Result<scene::RunOutcome> outcome = scene::runScene(s, options);
  bar.finish();
  if (!outcome) {
    std::cerr << "error: " << outcome.error().message << "\n";
    return 1;
  }
  if (!outcome.value().stable) {
    std::cerr << "error: simulation unstable: " << outcome.value().failure << "\n"
              << "results up to the last good step are in " << args.out << "/\n";
    return 3;
  }
  std::cerr << "done: " << outcome.value().steps_done << " steps; results in " << args.out
            << "/ (summary.json, wrench.csv, energy.csv, one .vtk per body)\n";
  return 0;
}

}  // namespace

void addRunCommand(CLI::App& app) {
  auto args = std::make_shared<RunArguments>();
  CLI::App* cmd = app.add_subcommand("run", "Run a scene headless and write its results");
  cmd->add_option("scene", args->scene, "Scene file (JSON, see docs/scene-format.md)")->required();
  cmd->add_option("--out", args->out, "Output directory")->capture_default_str();
  cmd->add_option("--steps", args->steps, "Number of steps (default: the scene's)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--threads", args->threads,
                  "Worker threads (default: the scene's; 0 = all cores)")
      ->check(CLI::NonNegativeNumber);
  cmd->callback([args] { setExitCode(run(*args)); });
}

}  // namespace torsion::cli
