#include "viewer_window.h"

#include <GLFW/glfw3.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <mutex>
#include <vector>

namespace torsion::viewer {

namespace {

// GLFW for the whole process: initialised by the first window, terminated with the last.
// `last_error` keeps GLFW's latest message, so a failed open can say why (no DISPLAY, ...); while
// windows are open, errors are also printed, as they happen in the middle of a frame.
struct GlfwLibrary {
  std::mutex mutex;
  int windows = 0;
  std::string last_error;
};

GlfwLibrary& glfwLibrary() {
  static GlfwLibrary library;
  return library;
}

void onGlfwError(int code, const char* text) {
  GlfwLibrary& library = glfwLibrary();
  library.last_error = text ? text : "";
  if (library.windows > 0) std::cerr << "glfw error " << code << ": " << library.last_error << "\n";
}

// Takes a reference on GLFW for one window; the error says why there is no window system.
Status acquireGlfw() {
  GlfwLibrary& library = glfwLibrary();
  std::lock_guard<std::mutex> lock(library.mutex);
  if (library.windows == 0) {
    library.last_error.clear();
    glfwSetErrorCallback(onGlfwError);
    if (!glfwInit()) {
      const std::string why =
          library.last_error.empty() ? "" : " (GLFW: " + library.last_error + ")";
      return Error{"no display for a window" + why + ": set DISPLAY, or run under xvfb-run"};
    }
  }
  ++library.windows;
  return Ok{};
}

void releaseGlfw() {
  GlfwLibrary& library = glfwLibrary();
  std::lock_guard<std::mutex> lock(library.mutex);
  if (--library.windows == 0) glfwTerminate();
}

ViewerWindow::InputState& inputOf(GLFWwindow* w) {
  return *static_cast<ViewerWindow::InputState*>(glfwGetWindowUserPointer(w));
}

}  // namespace

void dragCamera(render::Camera& camera, int button, double dx, double dy, int height) {
  const double h = std::max(1, height);
  if (button == GLFW_MOUSE_BUTTON_LEFT) {
    camera.orbit(-dx / h * 3, dy / h * 3);
  } else {
    camera.pan(-dx / h, dy / h);
  }
}

void scrollCamera(render::Camera& camera, double dy) {
  camera.zoom(std::pow(0.9, dy));
}

Result<std::unique_ptr<ViewerWindow>> ViewerWindow::open(const WindowSettings& settings) {
  if (Status glfw = acquireGlfw(); !glfw) return glfw.error();
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 2);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 1);
  glfwWindowHint(GLFW_SAMPLES, 4);
  GLFWwindow* window =
      glfwCreateWindow(settings.width, settings.height, settings.title.c_str(), nullptr, nullptr);
  if (!window) {
    const std::string why = glfwLibrary().last_error;
    releaseGlfw();
    return Error{"could not open an OpenGL 2.1 window" +
                 (why.empty() ? "" : " (GLFW: " + why + ")")};
  }
  std::unique_ptr<ViewerWindow> opened(new ViewerWindow(window));  // owns the window from here
  glfwSetWindowUserPointer(window, &opened->input_);
  glfwMakeContextCurrent(window);
  glfwSwapInterval(settings.vsync ? 1 : 0);
  const std::string missing = render::loadGlApi(opened->gl_, [](const char* name) -> void* {
    return reinterpret_cast<void*>(glfwGetProcAddress(name));
  });
  if (!missing.empty()) return Error{"the OpenGL context lacks " + missing};
  opened->gl_.Enable(GL_MULTISAMPLE);
  return opened;
}

ViewerWindow::~ViewerWindow() {
  glfwDestroyWindow(window_);
  releaseGlfw();
}

void ViewerWindow::makeCurrent() {
  glfwMakeContextCurrent(window_);
}

void ViewerWindow::connect(InputSink& sink) {
  input_.sink = &sink;
  glfwSetKeyCallback(window_, [](GLFWwindow* w, int key, int, int action, int mods) {
    if (action == GLFW_PRESS || action == GLFW_REPEAT)
      inputOf(w).sink->onKey(key, (mods & GLFW_MOD_SHIFT) != 0);
  });
  glfwSetCursorPosCallback(window_, [](GLFWwindow* w, double x, double y) {
    InputState& s = inputOf(w);
    const double dx = x - s.last_x, dy = y - s.last_y;
    s.last_x = x;
    s.last_y = y;
    const bool ctrl = glfwGetKey(w, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS ||
                      glfwGetKey(w, GLFW_KEY_RIGHT_CONTROL) == GLFW_PRESS;
    int width = 0, height = 0;
    glfwGetFramebufferSize(w, &width, &height);
    for (int b : {GLFW_MOUSE_BUTTON_LEFT, GLFW_MOUSE_BUTTON_RIGHT, GLFW_MOUSE_BUTTON_MIDDLE}) {
      if (glfwGetMouseButton(w, b) == GLFW_PRESS) {
        s.sink->onDrag(b, dx, dy, ctrl, height);
        break;
      }
    }
  });
  glfwSetScrollCallback(window_,
                        [](GLFWwindow* w, double, double dy) { inputOf(w).sink->onScroll(dy); });
}

void ViewerWindow::pollEvents() {
  glfwPollEvents();
}

bool ViewerWindow::closeRequested() const {
  return glfwWindowShouldClose(window_) != 0;
}

void ViewerWindow::requestClose() {
  glfwSetWindowShouldClose(window_, GLFW_TRUE);
}

void ViewerWindow::framebufferSize(int& width, int& height) const {
  glfwGetFramebufferSize(window_, &width, &height);
}

void ViewerWindow::swapBuffers() {
  glfwSwapBuffers(window_);
}

render::Image ViewerWindow::readPixels(int width, int height) const {
  render::Image image;
  image.width = width;
  image.height = height;
  const size_t row = 3 * static_cast<size_t>(width);
  std::vector<unsigned char> pixels(row * static_cast<size_t>(height));
  gl_.PixelStorei(GL_PACK_ALIGNMENT, 1);
  gl_.ReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, pixels.data());
  image.rgb.resize(pixels.size());
  for (int y = 0; y < height; ++y)  // GL rows go bottom to top
    std::copy_n(&pixels[static_cast<size_t>(height - 1 - y) * row], row, image.pixel(0, y));
  return image;
}

}  // namespace torsion::viewer
