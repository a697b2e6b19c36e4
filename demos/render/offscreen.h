#pragma once
// Headless pictures: an OSMesa (software OpenGL) context and a Renderer in one object.
// libOSMesa is opened at run time (dlopen), so the binary does not need it to start and the
// window path's libGL never meets it.

#include <memory>
#include <string>
#include <vector>

#include "image.h"
#include "renderer.h"
#include "torsion/result.h"

namespace torsion::render {

class OffscreenRenderer {
 public:
  /// A context for pictures of width x height, drawn at supersample times that size and averaged
  /// down (anti-aliasing). Errors: libOSMesa missing, or a context it cannot make.
  static Result<std::unique_ptr<OffscreenRenderer>> create(int width, int height,
                                                           int supersample = 2);
  ~OffscreenRenderer();
  OffscreenRenderer(const OffscreenRenderer&) = delete;
  OffscreenRenderer& operator=(const OffscreenRenderer&) = delete;

  /// Draws `frame` from `camera` (options.pixel_scale is set from the supersampling).
  Image render(const FrameData& frame, const Camera& camera, RenderOptions options = {});

  /// The camera that fits `frame` into this renderer's pictures drawn with `options`: the 3D
  /// view's aspect, and the scene kept below the HUD panel (frameCamera).
  Camera fitCamera(const FrameData& frame, RenderOptions options = {}) const;

  int width() const { return width_; }
  int height() const { return height_; }

  struct OsMesa;  ///< the dlopened library and its context (defined in offscreen.cpp)

 private:
  OffscreenRenderer() = default;
  std::unique_ptr<OsMesa> osmesa_;
  GlApi gl_;
  std::unique_ptr<Renderer> renderer_;
  std::vector<unsigned char> buffer_;  // RGBA, bottom row first
  int width_ = 0, height_ = 0, supersample_ = 1;
};

}  // namespace torsion::render
