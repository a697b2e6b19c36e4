#include "view_command.h"

#include <cstdio>
#include <iostream>
#include <memory>

#include "device_options.h"
#include "viewer.h"

namespace torsion::cli {

void addViewCommand(CLI::App& app, CommandAction& chosen) {
  auto options = std::make_shared<viewer::ViewerOptions>();
  auto size = std::make_shared<std::string>("1024x720");
  CLI::App* cmd = app.add_subcommand("view", "Open a scene in a window and drive it live");
  cmd->add_option("scene", options->scene,
                  "Scene file (JSON, see docs/scene-format.md) or the name of a demo scene")
      ->required();
  cmd->add_option("--size", *size, "Window size WxH")->capture_default_str();
  cmd->add_option("--threads", options->threads, "Worker threads (default: the scene's)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--frames", options->frames, "Quit after this many frames (tests)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--steps-per-frame", options->steps_per_frame,
                  "Take this many steps a frame instead of following the wall clock (tests)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--script", options->script,
                  "Synthetic input, one event a line: '<frame> key NAME [shift]', '<frame> drag "
                  "left|right|middle DX DY [ctrl]', '<frame> scroll DY'");
  cmd->add_option("--screenshot", options->screenshot, "Write the last frame to this PNG");
  addDeviceOptions(*cmd, options->devices);
  cmd->callback([&chosen, options, size] {
    chosen = [options, size] {
      if (std::sscanf(size->c_str(), "%dx%d", &options->width, &options->height) != 2 ||
          options->width < 64 || options->height < 64) {
        std::cerr << "error: --size '" << *size << "': expected WxH, at least 64x64\n";
        return 1;
      }
      return viewer::runViewer(*options);
    };
  });
}

}  // namespace torsion::cli
