#pragma once
// The interactive viewer: a scene stepping live in a GLFW window, drawn by torsion_render's
// Renderer. Input (real, or synthetic from a script for tests) goes through one set of handlers:
//   camera   left drag orbit, right or middle drag pan, wheel zoom, F reframe
//   hand     M take or leave manual control of the first hand (a new one when the scene has
//            none); arrows / PageUp / PageDown move it along x / y / z, with Shift rotate about
//            those axes; Ctrl + left drag moves it in the screen plane; G grab, U release
//   run      Space pause / run, N one step, R reset, Q or Escape quit
//   settings T / Shift+T dt x2 / /2, E / Shift+E Young's modulus x1.5 / /1.5, P / Shift+P
//            Poisson's ratio +-0.02, D / Shift+D stiffness damping x2 / /2, C next solver; a
//            change takes effect at the next step of the running simulation (no restart), is
//            logged on stdout ("viewer: live edit, world at step N, t = T s; DT ...") and kept
//            by a reset
// Simulated time follows the wall clock (pacing.h): several steps a frame when dt is shorter than
// a frame, slow motion when the steps cannot keep up ("0.4x REAL TIME" on the HUD), never more
// steps than fit in a frame's budget; --steps-per-frame N takes N steps a frame instead (tests).
// The HUD shows the live settings and a scrolling plot of the first hand's force and torque.
// Hands with a device (the scene's `device`, or --device HAND=TYPE[:ARG] as for `torsion run`)
// follow it through their haptic loops; M, G, U and the hand keys leave such a hand to its device.
//   tool     a tool (rigid body) with a `manual` device (--device TOOL=manual) takes the hand
//            keys and Ctrl + left drag instead: they move its device (manual_tool.h), G / U hold
//            and let go of its button 1 (a grasper closes and opens); M takes the first hand as
//            above, and M again gives the keys back to the tool

#include <string>

#include "device_parser.h"

namespace torsion::viewer {

struct ViewerOptions {
  std::string scene;
  int width = 1024, height = 720;
  int threads = -1;
  int frames = 0;                  ///< > 0: quit after this many frames (tests)
  int steps_per_frame = 0;         ///< > 0: this many steps a frame; 0: real-time pacing
  std::string script;              ///< synthetic input, one event per line (see viewer.cpp)
  std::string screenshot;          ///< PNG of the last frame, written on exit
  scene::DeviceOverrides devices;  ///< --device / --haptics, as for `torsion run`
};

/// Returns the process exit code: 0 clean exit, 1 bad input or no window, 3 simulation unstable.
int runViewer(const ViewerOptions& options);

}  // namespace torsion::viewer
