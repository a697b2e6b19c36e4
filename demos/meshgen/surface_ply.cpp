// Stanford PLY surfaces (.ply): ASCII, binary little endian and binary big endian.

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "surface_mesh.h"

namespace torsion::meshgen {

namespace {

struct Property {
  std::string name;
  std::string type;        // scalar type, or the item type of a list
  std::string count_type;  // list length type; empty for a scalar
};

struct Element {
  std::string name;
  long count = 0;
  std::vector<Property> properties;
};

int typeSize(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "int32" || type == "uint32" || type == "float" ||
      type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

// Values in the body, ASCII tokens or binary fields, read one number at a time.
class Body {
 public:
  Body(std::string_view bytes, const std::string& file, int format)
      : bytes_(bytes), file_(file), format_(format) {}

  double next(const std::string& type, const std::string& what) {
    if (format_ == 0) return nextText(what);
    const size_t n = static_cast<size_t>(typeSize(type));
    if (pos_ + n > bytes_.size()) fail("the file ends inside " + what);
    unsigned char raw[8];
    std::memcpy(raw, bytes_.data() + pos_, n);
    pos_ += n;
    if (format_ == 2) {  // big endian: reverse into this machine's (little endian) order
      for (size_t i = 0; i < n / 2; ++i)
        std::swap(raw[i], raw[n - 1 - i]);
    }
    if (type == "char" || type == "int8")
      return static_cast<double>(static_cast<std::int8_t>(raw[0]));
    if (type == "uchar" || type == "uint8") return static_cast<double>(raw[0]);
    if (n == 2) {
      std::uint16_t u;
      std::memcpy(&u, raw, 2);
      return type[0] == 'u' ? static_cast<double>(u)
                            : static_cast<double>(static_cast<std::int16_t>(u));
    }
    if (type == "float" || type == "float32") {
      float f;
      std::memcpy(&f, raw, 4);
      return static_cast<double>(f);
    }
    if (n == 4) {
      std::uint32_t u;
      std::memcpy(&u, raw, 4);
      return type[0] == 'u' ? static_cast<double>(u)
                            : static_cast<double>(static_cast<std::int32_t>(u));
    }
    double d;
    std::memcpy(&d, raw, 8);
    return d;
  }

  [[noreturn]] void fail(const std::string& message) const {
    throw std::runtime_error(file_ + ": " + message);
  }

 private:
  double nextText(const std::string& what) {
    while (pos_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[pos_])))
      ++pos_;
    if (pos_ >= bytes_.size()) fail("the file ends inside " + what);
    const size_t start = pos_;
    while (pos_ < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[pos_])))
      ++pos_;
    const std::string token(bytes_.substr(start, pos_ - start));
    char* end = nullptr;
    const double v = std::strtod(token.c_str(), &end);
    if (end != token.c_str() + token.size() || !std::isfinite(v))
      fail("not a number in " + what + ": '" + token.substr(0, 40) + "'");
    return v;
  }

  std::string_view bytes_;
  const std::string& file_;
  int format_;  // 0 ascii, 1 binary little endian, 2 binary big endian
  size_t pos_ = 0;
};

SurfaceMesh parsePlyOrThrow(std::string_view bytes, const std::string& file) {
  auto fail = [&](const std::string& message) -> void {
    throw std::runtime_error(file + ": " + message);
  };
  if (bytes.substr(0, 4) != "ply\n" && bytes.substr(0, 5) != "ply\r\n")
    fail("not a PLY file (it must start with the line 'ply')");
  const size_t header_end = bytes.find("end_header");
  if (header_end == std::string_view::npos) fail("no 'end_header' line");
  const size_t body_start = bytes.find('\n', header_end);
  if (body_start == std::string_view::npos) fail("nothing after 'end_header'");
  std::istringstream header{std::string(bytes.substr(0, header_end))};
  int format = -1;
  std::vector<Element> elements;
  int line_number = 0;
  for (std::string line; std::getline(header, line);) {
    ++line_number;
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    const std::string at = "header line " + std::to_string(line_number) + ": ";
    if (keyword == "format") {
      std::string name, version;
      words >> name >> version;
      if (name == "ascii")
        format = 0;
      else if (name == "binary_little_endian")
        format = 1;
      else if (name == "binary_big_endian")
        format = 2;
      else
        fail(at + "unknown format '" + name + "'");
    } else if (keyword == "element") {
      Element e;
      words >> e.name >> e.count;
      if (!words || e.count < 0 || e.count > 100'000'000) fail(at + "bad element line");
      elements.push_back(e);
    } else if (keyword == "property") {
      if (elements.empty()) fail(at + "a property before any element");
      Property p;
      std::string type;
      words >> type;
      if (type == "list")
        words >> p.count_type >> p.type >> p.name;
      else {
        p.type = type;
        words >> p.name;
      }
      if (!words || typeSize(p.type) == 0 || (!p.count_type.empty() && typeSize(p.count_type) == 0))
        fail(at + "bad property line '" + line.substr(0, 60) + "'");
      elements.back().properties.push_back(p);
    }
  }
  if (format < 0) fail("no 'format' line in the header");

  SurfaceMesh surface;
  bool has_vertices = false, has_faces = false;
  Body body(bytes.substr(body_start + 1), file, format);
  for (const Element& e : elements) {
    const bool vertex = e.name == "vertex", face = e.name == "face";
    has_vertices = has_vertices || vertex;
    has_faces = has_faces || face;
    for (long k = 0; k < e.count; ++k) {
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      int coordinates = 0;
      for (const Property& p : e.properties) {
        const std::string what = e.name + " " + std::to_string(k);
        if (p.count_type.empty()) {
          const double v = body.next(p.type, what);
          if (vertex && (p.name == "x" || p.name == "y" || p.name == "z")) {
            x[p.name[0] - 'x'] = v;
            ++coordinates;
          }
          continue;
        }
        const double n = body.next(p.count_type, what);
        if (!(n >= 0 && n <= 1000)) body.fail(what + ": a list of " + std::to_string(n) + " items");
        std::vector<int> items;
        for (int i = 0; i < static_cast<int>(n); ++i)
          items.push_back(static_cast<int>(body.next(p.type, what)));
        if (face && (p.name == "vertex_indices" || p.name == "vertex_index")) {
          if (items.size() < 3) body.fail(what + ": a face needs at least 3 vertices");
          for (size_t i = 1; i + 1 < items.size(); ++i)  // fan triangulation
            surface.triangles.push_back({items[0], items[i], items[i + 1]});
        }
      }
      if (vertex) {
        if (coordinates != 3) body.fail("vertex " + std::to_string(k) + " lacks x, y or z");
        surface.vertices.push_back(x);
      }
    }
  }
  if (!has_vertices || !has_faces) fail("needs a 'vertex' and a 'face' element");
  for (const auto& t : surface.triangles) {
    for (int v : t) {
      if (v < 0 || v >= static_cast<int>(surface.vertices.size()))
        fail("a face refers to vertex " + std::to_string(v) + " of " +
             std::to_string(surface.vertices.size()));
    }
  }
  return surface;
}

}  // namespace

Result<SurfaceMesh> parsePly(std::string_view bytes, const std::string& file) {
  try {
    return parsePlyOrThrow(bytes, file);
  } catch (const std::runtime_error& e) {
    return Error{e.what()};
  }
}

}  // namespace torsion::meshgen
