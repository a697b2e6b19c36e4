#pragma once
// 8-bit RGB pictures, rows top to bottom: PNG in and out (libpng) and the tolerant comparison the
// render tests use.

#include <cstdint>
#include <string>
#include <vector>

#include "torsion/result.h"

namespace torsion::render {

struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  ///< width * height * 3, row 0 at the top

  std::uint8_t* pixel(int x, int y) { return &rgb[offset(x, y)]; }
  const std::uint8_t* pixel(int x, int y) const { return &rgb[offset(x, y)]; }

 private:
  // x, y inside the image, hence not negative.
  size_t offset(int x, int y) const {
    return 3 * (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x));
  }
};

Status writePng(const Image& image, const std::string& path);
Result<Image> readPng(const std::string& path);

/// Averages factor x factor blocks (supersampling anti-aliasing). width and height must be
/// multiples of factor.
Image downsample(const Image& image, int factor);

/// How far apart two pictures of the same size are.
struct ImageDifference {
  double mean_abs = 0;            ///< mean |a - b| over all pixels and channels, in 0..255
  double differing_fraction = 0;  ///< pixels whose largest channel difference exceeds threshold
  int threshold = 0;
};

/// Errors: different sizes.
Result<ImageDifference> compareImages(const Image& a, const Image& b, int threshold);

}  // namespace torsion::render
