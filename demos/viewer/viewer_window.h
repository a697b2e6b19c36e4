#pragma once
// The viewer's GLFW window, shared by `torsion view` (viewer.h) and the passive viewer of a world
// a program steps itself (passive_viewer.h): an OpenGL 2.1 context with the GL entry points
// loaded, its input forwarded to an InputSink, and its pixels read back. GLFW is initialised with
// the first open window and terminated with the last, so several windows can live in one process
// (the Python module opens one per launch_passive). A window's methods, and its input callbacks,
// run on the thread that opened it.

#include <memory>
#include <string>

#include "camera.h"
#include "gl_api.h"
#include "image.h"
#include "torsion/result.h"

struct GLFWwindow;

namespace torsion::viewer {

/// Where a window's input goes: keys as GLFW key codes, drags in pixels of a window `height`
/// pixels high (button a GLFW_MOUSE_BUTTON_*), wheel steps.
class InputSink {
 public:
  virtual ~InputSink() = default;
  virtual void onKey(int key, bool shift) = 0;
  virtual void onDrag(int button, double dx, double dy, bool ctrl, int height) = 0;
  virtual void onScroll(double dy) = 0;
};

/// The camera's part of the input, the same in both viewers: left drag orbits, right or middle
/// drag pans, the wheel zooms.
void dragCamera(render::Camera& camera, int button, double dx, double dy, int height);
void scrollCamera(render::Camera& camera, double dy);

struct WindowSettings {
  int width = 1024, height = 720;
  std::string title = "torsion";
  bool vsync = true;  ///< swap on the display's refresh (false: as fast as frames come)
};

class ViewerWindow {
 public:
  /// Errors: no display ("no display for a window (GLFW: ...): set DISPLAY, or run under
  /// xvfb-run"), no OpenGL 2.1 context, missing GL entry points.
  static Result<std::unique_ptr<ViewerWindow>> open(const WindowSettings& settings);
  ~ViewerWindow();
  ViewerWindow(const ViewerWindow&) = delete;
  ViewerWindow& operator=(const ViewerWindow&) = delete;

  const render::GlApi& gl() const { return gl_; }
  /// Makes this window's context current on the calling thread.
  void makeCurrent();
  /// Forwards keys, drags and the wheel to `sink` (which must outlive the window, or be
  /// replaced) from glfwPollEvents.
  void connect(InputSink& sink);
  /// Delivers the pending input of every window (glfwPollEvents) to their sinks.
  static void pollEvents();
  /// The user asked to close it (the title bar's close button).
  bool closeRequested() const;
  /// Asks to close it, as the title bar's close button does (tests).
  void requestClose();
  /// The framebuffer's size in pixels (may differ from the window's on scaled displays).
  void framebufferSize(int& width, int& height) const;
  void swapBuffers();
  /// The back buffer as drawn, rows top to bottom (call before swapBuffers).
  render::Image readPixels(int width, int height) const;

  // For the input callbacks (viewer_window.cpp).
  struct InputState {
    InputSink* sink = nullptr;
    double last_x = 0, last_y = 0;
  };

 private:
  explicit ViewerWindow(GLFWwindow* window) : window_(window) {}
  GLFWwindow* window_;
  render::GlApi gl_;
  InputState input_;
};

}  // namespace torsion::viewer
