// The compiled half of torsion.viewer (torsion/viewer.py): _torsion._PassiveViewer, a window on a
// World that Python steps (demos/viewer/passive_viewer.h). Everything happens on the calling
// thread with the GIL held: sync() delivers the window's input, reads the world under its
// WorldGuard (a step running in another thread makes it raise) and draws, so the world is never
// read while it steps. Built without a window when GLFW was not found: opening one then raises.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>

#include "handles.h"
#include "py_convert.h"
#include "py_frame.h"
#if TORSION_PYTHON_VIEWER
#include "passive_viewer.h"
#endif

namespace torsion::python {

namespace {

#if TORSION_PYTHON_VIEWER
struct PyPassiveViewer {
  py::object owner;  ///< the torsion.World, kept alive while the viewer is
  PyWorld* world = nullptr;
  std::unique_ptr<viewer::PassiveViewer> viewer;

  viewer::PassiveViewer& onCallingThread(const char* what) const {
    if (!viewer->onOwnerThread())
      throw std::runtime_error(std::string("torsion.viewer: ") + what +
                               ": call the viewer from the thread that launched it");
    return *viewer;
  }
};

std::unique_ptr<PyPassiveViewer> openViewer(py::object world, int width, int height,
                                            const std::string& title) {
  if (!py::isinstance<PyWorld>(world))
    throw py::type_error("launch_passive: expected a torsion.World, got " +
                         std::string(py::str(world.get_type().attr("__name__"))));
  auto* w = world.cast<PyWorld*>();
  if (width < 64 || height < 64 || width > 16384 || height > 16384)
    throw py::value_error("launch_passive: width and height in [64, 16384] pixels, got " +
                          std::to_string(width) + " x " + std::to_string(height));
  viewer::WindowSettings settings;
  settings.width = width;
  settings.height = height;
  settings.vsync = false;  // sync() never waits for the display: the script sets the pace
  settings.title = !title.empty()              ? title
                   : !w->sceneSource().empty() ? "torsion: " + w->sceneSource()
                                               : "torsion";
  Result<std::unique_ptr<viewer::PassiveViewer>> opened = viewer::PassiveViewer::open(settings);
  if (!opened) throw std::runtime_error("launch_passive: " + opened.error().message);
  auto out = std::make_unique<PyPassiveViewer>();
  out->owner = std::move(world);
  out->world = w;
  out->viewer = std::move(opened).value();
  return out;
}

void syncViewer(PyPassiveViewer& v) {
  viewer::PassiveViewer& window = v.onCallingThread("sync");
  if (!window.pump()) return;  // closed: by the user, or by close()
  render::FrameData frame;
  {
    WorldGuard guard(*v.world);
    frame = captureWorldFrame(*v.world);
  }
  window.show(std::move(frame));
}

py::array captureViewer(PyPassiveViewer& v) {
  viewer::PassiveViewer& window = v.onCallingThread("capture");
  if (!window.isRunning())
    throw std::runtime_error("torsion.viewer: capture: the viewer is closed");
  if (window.frames() == 0)
    throw std::runtime_error("torsion.viewer: capture: nothing shown yet (call sync() first)");
  const render::Image image = window.capture();
  return copyArray(image.rgb.data(), image.height, image.width * 3)
      .attr("reshape")(image.height, image.width, 3);
}

void bindPassiveViewer(py::module_& m) {
  py::class_<PyPassiveViewer>(m, "_PassiveViewer",
                              "A window on a World that Python steps (torsion.viewer).")
      .def(py::init(&openViewer), py::arg("world"), py::arg("width"), py::arg("height"),
           py::arg("title"))
      .def("sync", &syncViewer, "Delivers the window's input and draws the world as it is now.")
      .def(
          "is_running", [](const PyPassiveViewer& v) { return v.viewer->isRunning(); },
          "False once the window is closed.")
      .def(
          "close", [](PyPassiveViewer& v) { v.onCallingThread("close").close(); },
          "Closes the window.")
      .def_property_readonly(
          "frame_count", [](const PyPassiveViewer& v) { return v.viewer->frames(); },
          "Frames drawn by sync().")
      .def_property_readonly(
          "real_time_factor", [](const PyPassiveViewer& v) { return v.viewer->realTimeFactor(); },
          "Simulated s per wall s between syncs, smoothed.")
      .def("capture", &captureViewer, "The last frame drawn, as (height, width, 3) uint8.")
      .def(
          "_request_close",
          [](PyPassiveViewer& v) { v.onCallingThread("_request_close").requestClose(); },
          "What the window's close button does: the next sync() closes it (tests).");
}
#else
void bindPassiveViewer(py::module_& m) {
  struct NoViewer {};
  py::class_<NoViewer>(m, "_PassiveViewer", "No window in this build (GLFW was not found).")
      .def(py::init([](const py::object&, int, int, const std::string&) -> NoViewer {
             throw std::runtime_error(
                 "launch_passive: this build of torsion has no window: GLFW (Debian's "
                 "libglfw3-dev) was not found when it was built");
           }),
           py::arg("world"), py::arg("width"), py::arg("height"), py::arg("title"));
}
#endif

}  // namespace

void bindViewer(py::module_& m) {
  bindPassiveViewer(m);
}

}  // namespace torsion::python
