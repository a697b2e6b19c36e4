#include "frame_recorder.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>

namespace torsion::render {

namespace fs = std::filesystem;

namespace {

std::string shellQuote(const std::string& s) {
  std::string q = "'";
  for (char c : s)
    q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace

std::optional<std::string> findOnPath(const std::string& program) {
  const char* path = std::getenv("PATH");
  if (!path) return std::nullopt;
  std::stringstream dirs(path);
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    const fs::path candidate = fs::path(dir) / program;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
  }
  return std::nullopt;
}

Result<std::unique_ptr<FrameRecorder>> FrameRecorder::create(const RecorderOptions& options) {
  std::error_code ec;
  fs::create_directories(options.directory, ec);
  if (ec)
    return Error{options.directory + ": cannot create the picture directory: " + ec.message()};
  Result<std::unique_ptr<OffscreenRenderer>> renderer =
      OffscreenRenderer::create(options.width, options.height);
  if (!renderer) return renderer.error();
  std::unique_ptr<FrameRecorder> r(new FrameRecorder);
  r->options_ = options;
  r->options_.every = std::max(1, options.every);
  r->renderer_ = std::move(renderer).value();
  return r;
}

Status FrameRecorder::onStep(scene::BuiltScene& scene, double steps_per_second) {
  if (scene.world->stepCount() % options_.every != 0) return Ok{};
  return capture(scene, steps_per_second);
}

Status FrameRecorder::capture(scene::BuiltScene& scene, double steps_per_second) {
  if (scene.world->stepCount() == last_step_) return Ok{};
  last_step_ = scene.world->stepCount();
  FrameData frame = captureFrame(scene, steps_per_second);
  stress_max_ = std::max(stress_max_, frame.stress_max);
  frame.stress_max = stress_max_;
  if (!camera_) {
    camera_ = renderer_->fitCamera(frame);
  }
  const Image image = renderer_->render(frame, *camera_);
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05d.png", frames_);
  Status written = writePng(image, (fs::path(options_.directory) / name).string());
  if (!written) return written;
  ++frames_;
  return Ok{};
}

std::string FrameRecorder::finish(const std::string& scene_name) {
  std::string what = std::to_string(frames_) + " pictures in " + options_.directory + "/";
  const std::optional<std::string> ffmpeg = findOnPath("ffmpeg");
  if (!ffmpeg || frames_ < 2) return what + (ffmpeg ? "" : " (no ffmpeg on PATH: no video)");
  const fs::path video = fs::path(options_.directory) / (scene_name + ".mp4");
  char fps[32];
  std::snprintf(fps, sizeof fps, "%g", options_.video_fps);
  const std::string command =
      shellQuote(*ffmpeg) + " -y -loglevel error -framerate " + fps + " -i " +
      shellQuote((fs::path(options_.directory) / "frame_%05d.png").string()) +
      " -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' -pix_fmt yuv420p -c:v libx264 " +
      shellQuote(video.string());
  if (std::system(command.c_str()) == 0) return what + " and the video " + video.string();
  return what + " (ffmpeg failed to make the video)";
}

}  // namespace torsion::render
