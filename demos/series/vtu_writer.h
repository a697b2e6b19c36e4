#pragma once
// VTK XML unstructured grids (.vtu,
// https://docs.vtk.org/en/latest/design_documents/VTKFileFormats.html) for ParaView time series:
// points, cells, point, cell and field data, all in one appended binary block, each array
// zlib-compressed when the build has zlib (vtkZLibDataCompressor, one block per array, UInt64
// headers) and raw otherwise. Numbers are stored as they are in memory (little endian Float64,
// Int64, UInt8), so they read back bit for bit.

#include <cstdint>
#include <string>
#include <vector>

namespace torsion::series {

/// VTK cell types used here.
enum class VtkCellType : std::uint8_t { kTriangle = 5, kTetra = 10, kQuadraticTetra = 24 };

class VtuBuilder {
 public:
  /// Points, 3 coordinates each (m).
  void setPoints(std::vector<double> xyz) { points_ = std::move(xyz); }
  /// One cell: its point indices in VTK's order for `type`.
  void addCell(VtkCellType type, const std::vector<std::int64_t>& points);
  /// Point or cell data: `components` values per point or cell.
  void addPointData(std::string name, int components, std::vector<double> values);
  void addCellData(std::string name, int components, std::vector<double> values);
  void addCellFlags(std::string name, std::vector<std::uint8_t> values);  ///< 0 or 1 per cell
  /// Field data: values that belong to the whole dataset (time, a wrench).
  void addFieldData(std::string name, std::vector<double> values);

  /// The .vtu file's bytes.
  std::string text() const;

  /// True when the arrays are zlib-compressed (the build found zlib).
  static bool compressed();

 private:
  struct Array {
    std::string name;
    std::string type;  // Float64, Int64, UInt8
    int components = 1;
    std::string bytes;
  };
  std::vector<double> points_;
  std::vector<std::int64_t> connectivity_, offsets_;
  std::vector<std::uint8_t> types_;
  std::vector<Array> point_data_, cell_data_, field_data_;
};

struct PvdEntry {
  double time = 0;   ///< s
  int part = 0;      ///< one part per body: ParaView shows each as its own block
  std::string file;  ///< relative to the .pvd
};

/// A ParaView collection (.pvd) listing the files of a time series.
std::string pvdText(const std::vector<PvdEntry>& entries);

}  // namespace torsion::series
