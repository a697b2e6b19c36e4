#include "vtu_writer.h"

#include <cstring>
#include <sstream>

#if TORSION_HAVE_ZLIB
#include <zlib.h>
#endif

namespace torsion::series {

namespace {

template <typename T>
std::string bytesOf(const std::vector<T>& values) {
  std::string bytes(values.size() * sizeof(T), '\0');
  if (!values.empty()) std::memcpy(bytes.data(), values.data(), bytes.size());
  return bytes;
}

void appendUInt64(std::string& out, std::uint64_t v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof v);
}

// One array's bytes as they go into the appended block: a header, then the data.
std::string encoded(const std::string& raw) {
  std::string out;
#if TORSION_HAVE_ZLIB
  // Compressed: [blocks = 1, block size, last block size, compressed size], then the block.
  uLongf size = compressBound(static_cast<uLong>(raw.size()));
  std::string block(size, '\0');
  compress2(reinterpret_cast<Bytef*>(block.data()), &size,
            reinterpret_cast<const Bytef*>(raw.data()), static_cast<uLong>(raw.size()),
            Z_DEFAULT_COMPRESSION);
  block.resize(size);
  appendUInt64(out, 1);
  appendUInt64(out, raw.size());
  appendUInt64(out, raw.size());
  appendUInt64(out, block.size());
  out += block;
#else
  appendUInt64(out, raw.size());  // raw: the byte count, then the bytes
  out += raw;
#endif
  return out;
}

std::string xmlName(const std::string& name) {
  std::string out;
  for (char c : name) {
    if (c == '"')
      out += "&quot;";
    else if (c == '&')
      out += "&amp;";
    else if (c == '<')
      out += "&lt;";
    else
      out += c;
  }
  return out;
}

}  // namespace

bool VtuBuilder::compressed() {
  return TORSION_HAVE_ZLIB != 0;
}

void VtuBuilder::addCell(VtkCellType type, const std::vector<std::int64_t>& points) {
  connectivity_.insert(connectivity_.end(), points.begin(), points.end());
  offsets_.push_back(static_cast<std::int64_t>(connectivity_.size()));
  types_.push_back(static_cast<std::uint8_t>(type));
}

void VtuBuilder::addPointData(std::string name, int components, std::vector<double> values) {
  point_data_.push_back({std::move(name), "Float64", components, bytesOf(values)});
}

void VtuBuilder::addCellData(std::string name, int components, std::vector<double> values) {
  cell_data_.push_back({std::move(name), "Float64", components, bytesOf(values)});
}

void VtuBuilder::addCellFlags(std::string name, std::vector<std::uint8_t> values) {
  cell_data_.push_back({std::move(name), "UInt8", 1, bytesOf(values)});
}

void VtuBuilder::addFieldData(std::string name, std::vector<double> values) {
  field_data_.push_back(
      {std::move(name), "Float64", static_cast<int>(values.size()), bytesOf(values)});
}

std::string VtuBuilder::text() const {
  std::ostringstream xml;
  std::string appended;
  auto array = [&](const Array& a, const char* indent, bool field) {
    xml << indent << "<DataArray type=\"" << a.type << "\" Name=\"" << xmlName(a.name) << "\"";
    if (field) xml << " NumberOfTuples=\"1\"";
    if (a.components != 1 || field) xml << " NumberOfComponents=\"" << a.components << "\"";
    xml << " format=\"appended\" offset=\"" << appended.size() << "\"/>\n";
    appended += encoded(a.bytes);
  };
  xml << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
         "header_type=\"UInt64\""
      << (compressed() ? " compressor=\"vtkZLibDataCompressor\"" : "") << ">\n"
      << "  <UnstructuredGrid>\n";
  if (!field_data_.empty()) {
    xml << "    <FieldData>\n";
    for (const Array& a : field_data_)
      array(a, "      ", true);
    xml << "    </FieldData>\n";
  }
  xml << "    <Piece NumberOfPoints=\"" << points_.size() / 3 << "\" NumberOfCells=\""
      << types_.size() << "\">\n";
  xml << "      <PointData>\n";
  for (const Array& a : point_data_)
    array(a, "        ", false);
  xml << "      </PointData>\n      <CellData>\n";
  for (const Array& a : cell_data_)
    array(a, "        ", false);
  xml << "      </CellData>\n      <Points>\n";
  array({"Points", "Float64", 3, bytesOf(points_)}, "        ", false);
  xml << "      </Points>\n      <Cells>\n";
  array({"connectivity", "Int64", 1, bytesOf(connectivity_)}, "        ", false);
  array({"offsets", "Int64", 1, bytesOf(offsets_)}, "        ", false);
  array({"types", "UInt8", 1, bytesOf(types_)}, "        ", false);
  xml << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n"
      << "  <AppendedData encoding=\"raw\">\n   _";
  return xml.str() + appended + "\n  </AppendedData>\n</VTKFile>\n";
}

std::string pvdText(const std::vector<PvdEntry>& entries) {
  std::ostringstream xml;
  xml.precision(17);
  xml << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      << "  <Collection>\n";
  for (const PvdEntry& e : entries)
    xml << "    <DataSet timestep=\"" << e.time << "\" part=\"" << e.part << "\" file=\""
        << xmlName(e.file) << "\"/>\n";
  xml << "  </Collection>\n</VTKFile>\n";
  return xml.str();
}

}  // namespace torsion::series
