#pragma once
// Shared by the render tests: one OSMesa renderer (400 x 300, 2x supersampled), scenes loaded
// from tests/data/render/ and captured as a FrameData with a fitted camera, stored references,
// and the tolerant picture comparison.
//
// Tolerances: a picture passes when the mean absolute difference is at most kMaxMeanAbs (of 255,
// per channel) and at most kMaxDifferingFraction of its pixels differ by more than
// kPixelThreshold in some channel. Another rasteriser (Mesa's llvmpipe vs softpipe, or a new
// Mesa) moves anti-aliased edge pixels and rounds shading differently by a few levels; that
// stays far below these bounds. Mesh lines are off in the compared pictures: a 1-pixel line
// rasterised one pixel over is the largest driver-dependent change and is not what these tests
// are about. What they are about changes 3 % to 30 % of the pixels (see the perturbation tests).

#include <string>

#include "camera.h"
#include "frame_data.h"
#include "image.h"
#include "renderer.h"

namespace torsion::render::test {

constexpr int kPixelThreshold = 24;
constexpr double kMaxMeanAbs = 1.5;
constexpr double kMaxDifferingFraction = 0.01;
constexpr int kWidth = 400, kHeight = 300;

RenderOptions compareOptions();  ///< mesh lines off (see above)

struct Rendered {
  FrameData frame;
  Camera camera;
};

/// tests/data/render/NAME.json after `steps` steps (its hands driven), captured, with the
/// camera fitted to that frame.
Rendered loadAndCapture(const std::string& name, int steps);

Image draw(const Rendered& scene, const FrameData& frame);

/// tests/data/render/NAME.png
std::string referencePath(const std::string& name);
Image reference(const std::string& name);
ImageDifference against(const Image& reference, const Image& picture);
bool passes(const ImageDifference& d);

/// Draws the scene, leaves the picture as render_actual_NAME.png in the working directory, and
/// compares it with the reference (or, with TORSION_UPDATE_REFERENCES set, rewrites the
/// reference and skips).
void expectMatchesReference(const std::string& name, const Rendered& scene);

/// The perturbed frame must fail the comparison with the reference, with a margin (more than
/// twice the allowed fraction of differing pixels): the tolerances are not so loose that they
/// hide what a reader of the picture would call wrong.
void expectCaught(const std::string& name, const Rendered& scene, const FrameData& perturbed,
                  const char* what);

}  // namespace torsion::render::test
