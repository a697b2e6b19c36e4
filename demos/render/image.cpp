#include "image.h"

#include <png.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "torsion/device/file_io.h"

namespace torsion::render {

namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

}  // namespace

namespace {

// libpng's output into memory, so the file is written whole or not at all (device/file_io.h).
void appendToString(png_structp png, png_bytep data, png_size_t length) {
  static_cast<std::string*>(png_get_io_ptr(png))
      ->append(reinterpret_cast<const char*>(data), length);
}
void flushNothing(png_structp /*png*/) {}

}  // namespace

Status writePng(const Image& image, const std::string& path) {
  std::string bytes;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_write_struct(&png, nullptr);
    return Error{path + ": libpng could not start"};
  }
  std::vector<png_const_bytep> rows(static_cast<size_t>(image.height));
  for (int y = 0; y < image.height; ++y)
    rows[static_cast<size_t>(y)] = image.pixel(0, y);
  // libpng reports errors by longjmp; nothing with a destructor is created after this point.
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return Error{path + ": libpng failed to write the picture"};
  }
  png_set_write_fn(png, &bytes, appendToString, flushNothing);
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.width),
               static_cast<png_uint_32>(image.height), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_write_rows(png, const_cast<png_bytepp>(rows.data()), static_cast<png_uint_32>(image.height));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  // A temporary beside it, then a rename: a picture is whole or absent, and only a regular file
  // (or nothing) is replaced.
  if (std::string failed = device::writeFileAtomically(path, bytes); !failed.empty())
    return Error{failed};
  return Ok{};
}

Result<Image> readPng(const std::string& path) {
  File file(std::fopen(path.c_str(), "rb"));
  if (!file) return Error{path + ": cannot open"};
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    return Error{path + ": libpng could not start"};
  }
  Image image;
  std::vector<png_bytep> rows;
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    return Error{path + ": not a readable PNG"};
  }
  png_init_io(png, file.get());
  png_read_info(png, info);
  // Whatever the file holds, read it as 8-bit RGB.
  png_set_expand(png);
  png_set_strip_16(png);
  png_set_strip_alpha(png);
  png_set_gray_to_rgb(png);
  png_read_update_info(png, info);
  image.width = static_cast<int>(png_get_image_width(png, info));
  image.height = static_cast<int>(png_get_image_height(png, info));
  image.rgb.resize(static_cast<size_t>(image.width) * static_cast<size_t>(image.height) * 3);
  rows.resize(static_cast<size_t>(image.height));
  for (int y = 0; y < image.height; ++y)
    rows[static_cast<size_t>(y)] = image.pixel(0, y);
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return image;
}

Image downsample(const Image& image, int factor) {
  if (factor <= 1) return image;
  Image out;
  out.width = image.width / factor;
  out.height = image.height / factor;
  out.rgb.resize(static_cast<size_t>(out.width) * static_cast<size_t>(out.height) * 3);
  const int area = factor * factor;
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      int sum[3] = {0, 0, 0};
      for (int dy = 0; dy < factor; ++dy) {
        for (int dx = 0; dx < factor; ++dx) {
          const std::uint8_t* p = image.pixel(factor * x + dx, factor * y + dy);
          for (int c = 0; c < 3; ++c)
            sum[c] += p[c];
        }
      }
      for (int c = 0; c < 3; ++c)
        out.pixel(x, y)[c] = static_cast<std::uint8_t>((sum[c] + area / 2) / area);
    }
  }
  return out;
}

Result<ImageDifference> compareImages(const Image& a, const Image& b, int threshold) {
  if (a.width != b.width || a.height != b.height) {
    return Error{"pictures differ in size: " + std::to_string(a.width) + "x" +
                 std::to_string(a.height) + " and " + std::to_string(b.width) + "x" +
                 std::to_string(b.height)};
  }
  ImageDifference d;
  d.threshold = threshold;
  const size_t pixels = static_cast<size_t>(a.width) * static_cast<size_t>(a.height);
  if (pixels == 0) return d;
  long total = 0;
  size_t differing = 0;
  for (size_t i = 0; i < pixels; ++i) {
    int largest = 0;
    for (size_t c = 0; c < 3; ++c) {
      const int diff = std::abs(int(a.rgb[3 * i + c]) - int(b.rgb[3 * i + c]));
      total += diff;
      if (diff > largest) largest = diff;
    }
    if (largest > threshold) ++differing;
  }
  d.mean_abs = static_cast<double>(total) / static_cast<double>(3 * pixels);
  d.differing_fraction = static_cast<double>(differing) / static_cast<double>(pixels);
  return d;
}

}  // namespace torsion::render
