#include "passive_viewer.h"

#include <GLFW/glfw3.h>

#include <algorithm>
#include <utility>

#include "pacing.h"

namespace torsion::viewer {

namespace {

// Camera fitted to `frame` in a window of width x height pixels, below the HUD (as torsion view).
render::Camera fittedCamera(const render::FrameData& frame, int width, int height) {
  return render::frameCamera(
      frame, double(render::sceneViewportWidth(width, height, {})) / std::max(1, height),
      render::hudHeightFraction(frame, height, {}));
}

}  // namespace

Result<std::unique_ptr<PassiveViewer>> PassiveViewer::open(const WindowSettings& settings) {
  Result<std::unique_ptr<ViewerWindow>> window = ViewerWindow::open(settings);
  if (!window) return window.error();
  std::unique_ptr<PassiveViewer> viewer(new PassiveViewer(std::move(window).value()));
  viewer->window_->connect(*viewer);
  return viewer;
}

PassiveViewer::PassiveViewer(std::unique_ptr<ViewerWindow> window)
    : window_(std::move(window)),
      renderer_(std::make_unique<render::Renderer>(window_->gl())),
      owner_(std::this_thread::get_id()) {}

PassiveViewer::~PassiveViewer() {
  close();
}

bool PassiveViewer::pump() {
  if (!window_) return false;
  ViewerWindow::pollEvents();
  if (window_ && (quit_ || window_->closeRequested())) close();
  return isRunning();
}

void PassiveViewer::show(render::FrameData frame) {
  if (!window_) return;
  window_->makeCurrent();
  int width = 0, height = 0;
  window_->framebufferSize(width, height);
  measurePace(frame);
  recordWrench(frame);
  addNotes(frame);
  if (!framed_) {
    camera_ = fittedCamera(frame, width, height);
    framed_ = true;
  }
  renderer_->draw(frame, camera_, width, height, render::RenderOptions{});
  window_->swapBuffers();
  ++frames_;
  last_ = std::move(frame);
}

void PassiveViewer::close() {
  renderer_.reset();  // before the window whose GL entry points it holds
  window_.reset();
}

render::Image PassiveViewer::capture() {
  if (!window_ || !last_) return {};
  window_->makeCurrent();
  int width = 0, height = 0;
  window_->framebufferSize(width, height);
  renderer_->draw(*last_, camera_, width, height, render::RenderOptions{});
  return window_->readPixels(width, height);
}

void PassiveViewer::onKey(int key, bool) {
  if (key == GLFW_KEY_Q || key == GLFW_KEY_ESCAPE) quit_ = true;
  if (key == GLFW_KEY_F) framed_ = false;
}

void PassiveViewer::onDrag(int button, double dx, double dy, bool, int height) {
  dragCamera(camera_, button, dx, dy, height);
}

void PassiveViewer::onScroll(double dy) {
  scrollCamera(camera_, dy);
}

void PassiveViewer::measurePace(const render::FrameData& frame) {
  const auto now = std::chrono::steady_clock::now();
  if (last_ && frame.step > last_->step) {
    const double wall = std::chrono::duration<double>(now - last_wall_).count();
    if (wall > 0) {
      const double factor = (frame.time - last_->time) / wall;
      const double rate = (frame.step - last_->step) / wall;
      const bool first = factor_ <= 0;
      factor_ = first ? factor : factor_ + 0.1 * (factor - factor_);
      steps_per_second_ = first ? rate : steps_per_second_ + 0.1 * (rate - steps_per_second_);
    }
  }
  if (!last_ || frame.step != last_->step) last_wall_ = now;
}

void PassiveViewer::recordWrench(const render::FrameData& frame) {
  static constexpr size_t kHistory = 300;  // as torsion view: the last 300 steps
  if (frame.hands.empty() || (last_ && frame.step == last_->step)) return;
  const std::string& name = frame.hands.front().name;
  const auto wrench = std::find_if(frame.wrenches.begin(), frame.wrenches.end(),
                                   [&](const render::WrenchReadout& w) { return w.name == name; });
  if (wrench == frame.wrenches.end()) return;
  // Another hand, or a clock gone back (restore_state): a new plot.
  if (history_.name != name || (!history_.times.empty() && frame.time < history_.times.back()))
    history_ = render::WrenchHistory{};
  history_.name = name;
  history_.times.push_back(frame.time);
  history_.forces.push_back(wrench->force);
  history_.torques.push_back(wrench->torque);
  if (history_.times.size() > kHistory) {
    history_.times.erase(history_.times.begin());
    history_.forces.erase(history_.forces.begin());
    history_.torques.erase(history_.torques.begin());
  }
}

void PassiveViewer::addNotes(render::FrameData& frame) const {
  frame.steps_per_second = steps_per_second_;
  if (!history_.times.empty()) frame.plots.push_back(history_);
  frame.notes.push_back("PASSIVE: THE SCRIPT STEPS THE WORLD" +
                        (factor_ > 0 ? "  " + realTimeNote(factor_) : std::string()));
  frame.notes.emplace_back("KEYS F Q  DRAG ORBIT  RIGHT DRAG PAN  WHEEL ZOOM");
}

}  // namespace torsion::viewer
