#pragma once
// A window on a world that its program steps: the Python module's torsion.viewer.launch_passive
// (docs/python.md, "Watching a world"), after MuJoCo's passive viewer. The same window and
// picture as `torsion view` (viewer_window.h, torsion_render's Renderer: stress map, hands,
// wrenches and their plot, HUD), but it never steps or changes the world: the program takes a
// FrameData of its world (render::captureFrame) and hands it to show(). Its keys move the camera
// only: drags orbit and pan, the wheel zooms, F reframes, Q or Escape close the window.
//
// Threads: everything happens in the calls, on the thread that opened the viewer (pump() delivers
// the window's input, show() draws), so the world is read only while the program is in show()'s
// caller, never concurrently with a step. Between two calls the window is not redrawn and its
// input waits.

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "camera.h"
#include "frame_data.h"
#include "image.h"
#include "renderer.h"
#include "torsion/result.h"
#include "viewer_window.h"

namespace torsion::viewer {

class PassiveViewer : public InputSink {
 public:
  /// Opens the window (ViewerWindow::open's errors: no display, no OpenGL 2.1).
  static Result<std::unique_ptr<PassiveViewer>> open(const WindowSettings& settings);
  ~PassiveViewer() override;
  PassiveViewer(const PassiveViewer&) = delete;
  PassiveViewer& operator=(const PassiveViewer&) = delete;

  /// Whether the calling thread is the one that opened the viewer (the only one that may call
  /// pump, show, capture and close).
  bool onOwnerThread() const { return std::this_thread::get_id() == owner_; }
  /// Delivers the window's pending input; closes the window when the user asked to (its close
  /// button, Q, Escape). Returns isRunning().
  bool pump();
  /// Draws `frame` and shows it (nothing once closed). The HUD adds the program's pace, measured
  /// from the frames' clocks between two calls, and the first hand's wrench plot.
  void show(render::FrameData frame);
  bool isRunning() const { return window_ != nullptr; }
  /// Closes the window (again: nothing).
  void close();
  /// What the window's close button does: the next pump() closes it (tests).
  void requestClose() {
    if (window_) window_->requestClose();
  }
  /// Frames shown so far.
  int frames() const { return frames_; }
  /// The last frame shown, drawn again into the window's back buffer and read back (rows top to
  /// bottom); an empty image before the first frame and once closed.
  render::Image capture();
  /// Simulated s per wall s between the last two frames that advanced the clock, smoothed; 0
  /// before two such frames.
  double realTimeFactor() const { return factor_; }

  void onKey(int key, bool shift) override;
  void onDrag(int button, double dx, double dy, bool ctrl, int height) override;
  void onScroll(double dy) override;

 private:
  explicit PassiveViewer(std::unique_ptr<ViewerWindow> window);
  /// The pace between the previous frame shown and `frame` (HUD, realTimeFactor).
  void measurePace(const render::FrameData& frame);
  /// The first hand's wrench at each new step, for the scrolling plot.
  void recordWrench(const render::FrameData& frame);
  void addNotes(render::FrameData& frame) const;

  std::unique_ptr<ViewerWindow> window_;
  std::unique_ptr<render::Renderer> renderer_;  // draws with window_'s GL entry points
  std::thread::id owner_;
  render::Camera camera_;
  bool framed_ = false;  // the camera fits the scene (false: fit at the next frame, F)
  bool quit_ = false;
  int frames_ = 0;
  std::optional<render::FrameData> last_;  // the last frame shown, for capture()
  std::chrono::steady_clock::time_point last_wall_;
  double factor_ = 0;
  double steps_per_second_ = 0;
  render::WrenchHistory history_;
};

}  // namespace torsion::viewer
