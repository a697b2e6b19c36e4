#pragma once
// Draws a FrameData with OpenGL 1.x (compatibility profile; OSMesa and any desktop driver have
// it): lit FEM surfaces coloured by von Mises stress with their mesh lines, grabbed nodes in
// orange (the report's Figure 4.2), light stripes along elongated bodies (they wind when twisted),
// rigid bodies, the ground, each hand's axes (i red, j green, k blue) and plane, and an overlay
// (overlay.cpp) with the HUD (time, steps/s, wrenches as magnitudes and bars), the colour legend
// and the viewer's notes and wrench plot. Knows nothing of windows or files: the caller makes a
// context current.

#include <string>
#include <vector>

#include "camera.h"
#include "frame_data.h"
#include "gl_api.h"

namespace torsion::render {

struct RenderOptions {
  bool mesh_lines = true;  ///< surface triangle edges over the shading (they show the twist)
  bool stress = true;      ///< colour by stress; otherwise a plain body colour
  bool hud = true;
  bool legend = true;
  double pixel_scale = 1;  ///< line widths, points and text grow by this (supersampling)
};

/// Grabbed nodes (the report's Figure 4.2): orange, a colour the stress map never takes.
inline const Eigen::Vector3d kGrabbedOrange{1.0, 0.5, 0.0};

/// Size of one pixel of the HUD font, in framebuffer pixels: about height / 480 picture pixels,
/// a whole number of drawn pixels (half pixels when supersampled).
double textScale(int height, const RenderOptions& options);
/// Width of the 3D view: the picture minus the legend's strip on the right. Fit cameras with
/// the aspect sceneViewportWidth / height.
int sceneViewportWidth(int width, int height, const RenderOptions& options);
/// Fraction of the picture's height covered by the HUD panel at the top left (0 without HUD):
/// frameCamera keeps the scene below it.
double hudHeightFraction(const FrameData& frame, int height, const RenderOptions& options);

class Renderer {
 public:
  /// `gl` must stay valid, and its context current, while draw() runs.
  explicit Renderer(const GlApi& gl) : gl_(gl) {}

  /// Draws into the current framebuffer of width x height pixels.
  void draw(const FrameData& frame, const Camera& camera, int width, int height,
            const RenderOptions& options);

 private:
  void drawBackground();
  void drawGround(const FrameData& frame, const Eigen::Vector3d& up);
  void drawBodies(const FrameData& frame, const RenderOptions& options);
  /// The body's stripes (BodyDrawData::stripes) as light lines on its surface.
  void drawStripes(const BodyDrawData& body, const RenderOptions& options);
  // Rigid bodies (renderer_rigids.cpp).
  void drawRigids(const FrameData& frame);
  /// A capsule of `radius` whose cap centres lie +-half_height along local `axis` (0 x, 1 y,
  /// 2 z); half_height 0 is a sphere.
  void drawRound(const Eigen::Isometry3d& pose, double radius, double half_height, int axis);
  void drawBox(const Eigen::Isometry3d& pose, const Eigen::Vector3d& half_extents);
  /// A hull's or mesh's triangles, flat-shaded with their right-hand-rule normals.
  void drawTriangles(const RigidDrawData& rigid);
  void drawHands(const FrameData& frame, const RenderOptions& options);
  // The 2D overlay (overlay.cpp), in pixels with y down.
  void drawOverlay(const FrameData& frame, int width, int height, const RenderOptions& options);
  void drawHud(const FrameData& frame, double scale);
  void drawNotes(const FrameData& frame, int height, double scale);
  void drawLegend(const FrameData& frame, int width, int height, double scale);
  void drawWrenchPlot(const WrenchHistory& history, double x, double y, double width, double scale);
  /// A signed bar: a grey track of `width` with a coloured part from its middle, value / scale
  /// of half the width long.
  void drawBar(double x, double y, double width, double height, double value, double scale,
               const Eigen::Vector3d& colour);
  /// Text at pixel (x, y) = its top-left corner, y down; returns the width drawn.
  double drawText(double x, double y, double scale, const std::string& text);
  void quad2d(double x0, double y0, double x1, double y1);

  const GlApi& gl_;
  std::vector<float> colours_;  // scratch: per-vertex RGB of the body being drawn
  Eigen::Vector3d eye_ = Eigen::Vector3d::Zero();  // the camera's position in this draw()
};

}  // namespace torsion::render
