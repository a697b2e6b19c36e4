#pragma once
// Writes a scene's pictures while it runs headless: DIR/frame_00000.png (before the first step),
// then one every `every` steps, all from one camera fitted to the first frame and with a stress
// scale that only grows, so a sequence plays as a steady video. finish() makes DIR/<scene>.mp4
// when an `ffmpeg` command is on PATH.

#include <memory>
#include <optional>
#include <string>

#include "offscreen.h"
#include "scene_builder.h"

namespace torsion::render {

struct RecorderOptions {
  std::string directory;
  int width = 800;
  int height = 600;
  int every = 10;  ///< steps between pictures
  double video_fps = 25;
};

class FrameRecorder {
 public:
  /// Errors: the directory cannot be made, or no OSMesa.
  static Result<std::unique_ptr<FrameRecorder>> create(const RecorderOptions& options);

  /// Call before the first step and after each step; draws when the step count is a multiple of
  /// `every`. Errors: a picture that cannot be written.
  Status onStep(scene::BuiltScene& scene, double steps_per_second);
  /// Draws the current state whatever the step (the last one of a run).
  Status capture(scene::BuiltScene& scene, double steps_per_second);

  /// Encodes the pictures into an MP4 if ffmpeg is on PATH. Returns a line for the user saying
  /// what was written.
  std::string finish(const std::string& scene_name);

  int framesWritten() const { return frames_; }

 private:
  FrameRecorder() = default;
  RecorderOptions options_;
  std::unique_ptr<OffscreenRenderer> renderer_;
  std::optional<Camera> camera_;
  double stress_max_ = 0;
  int frames_ = 0;
  int last_step_ = -1;
};

/// The full path of `program` if an executable of that name is on PATH.
std::optional<std::string> findOnPath(const std::string& program);

}  // namespace torsion::render
