#include "run_comparison.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "torsion/device/file_io.h"
#include "torsion/device/json_check.h"
#include "torsion/mesh/vtk_format.h"

namespace torsion::cli {

namespace {

namespace fs = std::filesystem;

// summary.json keys that say how a result was obtained, not what it is: shown when they differ.
const std::set<std::string> kNotedKeys = {
    "schema_version",    "torsion_version",  "git_commit",     "bullet_precision",
    "threads",           "linear_solver",    "preconditioner", "tolerance",
    "solver_iterations", "final_state_hash", "kernel_path"};
// The same, for a key of every body (bodies[i].<key>).
const std::set<std::string> kNotedBodyKeys = {"renumbered"};
// Keys that differ between any two runs (timings) or name files: not shown.
const std::set<std::string> kIgnoredKeys = {"ms_per_step", "outputs", "scene_file", "haptics",
                                            "haptic_warnings"};

std::string format(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

bool within(double run, double reference, double scale, const ComparisonTolerance& t) {
  return std::abs(run - reference) <= t.relative * scale + t.absolute;
}

Result<nlohmann::json> readSummary(const fs::path& directory) {
  std::string text;
  const fs::path path = directory / "summary.json";
  if (std::string error = device::readRegularFile(path.string(), text); !error.empty())
    return Error{error};
  // The strict pass bounds the nesting before anything walks the document (flatten recurses).
  if (const auto fault = device::findJsonTextFault(text)) {
    const std::string where =
        fault->line > 0 ? ":" + std::to_string(fault->line) + ":" + std::to_string(fault->column)
                        : std::string();
    return Error{path.string() + where + ": invalid JSON: " + fault->what};
  }
  nlohmann::json summary = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (summary.is_discarded() || !summary.is_object())
    return Error{path.string() + ": not a JSON object"};
  return summary;
}

// Every leaf of a JSON value with its key path ("bodies[0].nodes").
void flatten(const nlohmann::json& value, const std::string& path,
             std::vector<std::pair<std::string, nlohmann::json>>& leaves) {
  if (value.is_object()) {
    for (const auto& [key, item] : value.items())
      flatten(item, path.empty() ? key : path + "." + key, leaves);
  } else if (value.is_array()) {
    for (size_t i = 0; i < value.size(); ++i)
      flatten(value[i], path + "[" + std::to_string(i) + "]", leaves);
  } else {
    leaves.emplace_back(path, value);
  }
}

void compareSummaries(const nlohmann::json& run, const nlohmann::json& reference,
                      const ComparisonTolerance& tolerance, RunComparison& out) {
  std::vector<std::pair<std::string, nlohmann::json>> run_leaves, reference_leaves;
  flatten(run, "", run_leaves);
  flatten(reference, "", reference_leaves);
  std::map<std::string, nlohmann::json> run_by_path(run_leaves.begin(), run_leaves.end());
  std::map<std::string, nlohmann::json> reference_by_path(reference_leaves.begin(),
                                                          reference_leaves.end());
  int compared = 0, differing = 0;
  std::vector<std::string> lines;
  auto top_key = [](const std::string& path) { return path.substr(0, path.find_first_of(".[")); };
  std::set<std::string> paths;
  for (const auto& [path, value] : run_by_path)
    paths.insert(path);
  for (const auto& [path, value] : reference_by_path)
    paths.insert(path);
  for (const std::string& path : paths) {
    const std::string key = top_key(path);
    if (kIgnoredKeys.count(key) != 0) continue;
    const auto r = run_by_path.find(path);
    const auto f = reference_by_path.find(path);
    const bool noted =
        kNotedKeys.count(key) != 0 ||
        (key == "bodies" && kNotedBodyKeys.count(path.substr(path.find_last_of('.') + 1)) != 0);
    if (r == run_by_path.end() || f == reference_by_path.end()) {
      const std::string side = r == run_by_path.end() ? "reference only" : "run only";
      if (noted) {
        lines.push_back("  note " + path + ": " + side);
      } else {
        lines.push_back("  DIFF " + path + ": " + side);
        ++differing;
      }
      continue;
    }
    const nlohmann::json& a = r->second;
    const nlohmann::json& b = f->second;
    bool same = a == b;
    if (!same && a.is_number() && b.is_number()) {
      const double x = a.get<double>(), y = b.get<double>();
      same = within(x, y, std::max(std::abs(x), std::abs(y)), tolerance);
    }
    if (noted) {
      if (key == "final_state_hash" && same)
        lines.push_back("  same final_state_hash: the final states are identical bit for bit");
      else if (!same)
        lines.push_back("  note " + path + ": " + a.dump() + " (reference " + b.dump() + ")");
      continue;
    }
    ++compared;
    if (!same) {
      lines.push_back("  DIFF " + path + ": " + a.dump() + " (reference " + b.dump() + ")");
      ++differing;
    }
  }
  out.report.push_back("summary.json: " + std::to_string(compared) + " values compared, " +
                       std::to_string(differing) + " differ");
  out.report.insert(out.report.end(), lines.begin(), lines.end());
  out.differences += differing;
}

struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
};

std::vector<std::string> splitCommas(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream stream(line);
  for (std::string cell; std::getline(stream, cell, ',');)
    cells.push_back(cell);
  return cells;
}

Result<Csv> readCsv(const fs::path& path) {
  std::string text;
  if (std::string error = device::readRegularFile(path.string(), text); !error.empty())
    return Error{error};
  // The runner writes every row whole with its line end: a last line without one was torn (the
  // writer was killed, or the file was cut), and is refused rather than read as a short row.
  if (!text.empty() && text.back() != '\n') {
    const auto last_line = 1 + std::count(text.begin(), text.end(), '\n');
    return Error{path.string() + ":" + std::to_string(last_line) +
                 ": the last row ends without its newline: a torn row"};
  }
  std::stringstream lines(text);
  Csv csv;
  std::string line;
  if (!std::getline(lines, line)) return Error{path.string() + ": empty"};
  csv.header = splitCommas(line);
  for (int number = 2; std::getline(lines, line); ++number) {
    std::vector<double> row;
    for (const std::string& cell : splitCommas(line)) {
      char* end = nullptr;
      row.push_back(std::strtod(cell.c_str(), &end));
      if (end == cell.c_str())
        return Error{path.string() + ":" + std::to_string(number) + ": not a number: " + cell};
    }
    if (row.size() != csv.header.size())
      return Error{path.string() + ":" + std::to_string(number) + ": " +
                   std::to_string(row.size()) + " values, the header has " +
                   std::to_string(csv.header.size())};
    csv.rows.push_back(std::move(row));
  }
  return csv;
}

// The kind of quantity a column holds, by its suffix: numbers are judged against the largest
// magnitude of their kind in the reference file (a fixed base that carries no load is judged
// against the hand's force, not against its own round-off). Other columns are their own kind.
std::string columnKind(const std::string& name) {
  const std::string suffix =
      name.substr(name.rfind('.') == std::string::npos ? 0 : name.rfind('.') + 1);
  static const std::map<std::string, std::string> kinds = {
      {"fx", "force"},       {"fy", "force"},       {"fz", "force"},       {"tx", "torque"},
      {"ty", "torque"},      {"tz", "torque"},      {"kinetic", "energy"}, {"elastic", "energy"},
      {"x", "position"},     {"y", "position"},     {"z", "position"},     {"qx", "orientation"},
      {"qy", "orientation"}, {"qz", "orientation"}, {"qw", "orientation"}, {"vx", "velocity"},
      {"vy", "velocity"},    {"vz", "velocity"}};
  if (name.find('.') == std::string::npos) return name;
  const auto kind = kinds.find(suffix);
  return kind == kinds.end() ? name : kind->second;
}

// Columns that report the solver's effort rather than the result.
bool isSolverColumn(const std::string& name) {
  return name == "iterations" || name == "relative_residual";
}

Status compareCsv(const std::string& name, const fs::path& run_dir, const fs::path& reference_dir,
                  const ComparisonTolerance& tolerance, RunComparison& out) {
  if (!fs::exists(reference_dir / name)) return Ok{};
  if (!fs::exists(run_dir / name)) {
    out.report.push_back(name + ": DIFF missing from the run");
    ++out.differences;
    return Ok{};
  }
  Result<Csv> run = readCsv(run_dir / name);
  if (!run) return run.error();
  Result<Csv> reference = readCsv(reference_dir / name);
  if (!reference) return reference.error();
  const Csv& a = run.value();
  const Csv& b = reference.value();
  if (a.header != b.header || a.rows.size() != b.rows.size()) {
    out.report.push_back(name + ": DIFF " +
                         (a.header != b.header
                              ? std::string("the columns differ")
                              : std::to_string(a.rows.size()) + " rows (reference " +
                                    std::to_string(b.rows.size()) + ")"));
    ++out.differences;
    return Ok{};
  }
  std::map<std::string, double> kind_scale;
  for (size_t c = 0; c < b.header.size(); ++c) {
    double& scale = kind_scale[columnKind(b.header[c])];
    for (const auto& row : b.rows)
      scale = std::max(scale, std::abs(row[c]));
  }
  int differing = 0;
  double worst = 0;  // largest |difference| / scale of its kind
  std::string worst_at;
  for (size_t c = 0; c < b.header.size(); ++c) {
    if (isSolverColumn(b.header[c])) continue;
    const double scale = kind_scale[columnKind(b.header[c])];
    int column_differing = 0;
    std::string first;
    for (size_t r = 0; r < b.rows.size(); ++r) {
      const double x = a.rows[r][c], y = b.rows[r][c];
      const double relative = scale > 0 ? std::abs(x - y) / scale : std::abs(x - y);
      if (relative > worst || !std::isfinite(relative)) {
        worst = relative;
        worst_at = b.header[c] + " row " + std::to_string(r + 1);
      }
      if (!within(x, y, scale, tolerance) || std::isnan(x) != std::isnan(y)) {
        if (column_differing++ == 0)
          first = "row " + std::to_string(r + 1) + ": " + format(x) + " (reference " + format(y) +
                  ", scale " + format(scale) + ")";
      }
    }
    if (column_differing > 0) {
      out.report.push_back("  DIFF " + name + " " + b.header[c] + ": " +
                           std::to_string(column_differing) + " rows differ, first " + first);
      ++differing;
    }
  }
  out.report.insert(out.report.end() - differing,
                    name + ": " + std::to_string(b.rows.size()) + " rows, " +
                        std::to_string(b.header.size()) + " columns; largest difference " +
                        format(worst) + " of its kind's scale" +
                        (worst_at.empty() ? "" : " (" + worst_at + ")"));
  out.differences += differing;
  return Ok{};
}

Status compareVtk(const std::string& name, const fs::path& run_dir, const fs::path& reference_dir,
                  const ComparisonTolerance& tolerance, RunComparison& out) {
  if (!fs::exists(run_dir / name)) {
    out.report.push_back(name + ": DIFF missing from the run");
    ++out.differences;
    return Ok{};
  }
  std::vector<RawTetMesh> meshes;
  for (const fs::path& dir : {run_dir, reference_dir}) {
    std::string text;
    const std::string path = (dir / name).string();
    if (std::string error = device::readRegularFile(path, text); !error.empty())
      return Error{error};
    Result<RawTetMesh> mesh = parseVtk(text, path);
    if (!mesh) return mesh.error();
    meshes.push_back(std::move(mesh).value());
  }
  const std::vector<Eigen::Vector3d>& a = meshes[0].positions;
  const std::vector<Eigen::Vector3d>& b = meshes[1].positions;
  if (a.size() != b.size() || meshes[0].tets.size() != meshes[1].tets.size()) {
    out.report.push_back(name + ": DIFF " + std::to_string(a.size()) + " nodes (reference " +
                         std::to_string(b.size()) + ")");
    ++out.differences;
    return Ok{};
  }
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Eigen::Vector3d& x : b) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  const double size = b.empty() ? 0.0 : (hi - lo).norm();
  double worst = 0;
  size_t worst_node = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const double d = (a[i] - b[i]).norm();
    if (d > worst || std::isnan(d)) {
      worst = d;
      worst_node = i;
    }
  }
  const bool same = within(worst, 0.0, size, tolerance);
  out.report.push_back(std::string(same ? "" : "  DIFF ") + name + ": " + std::to_string(a.size()) +
                       " nodes; largest position difference " + format(worst) + " m (node " +
                       std::to_string(worst_node) + ", " + format(size > 0 ? worst / size : 0.0) +
                       " of the body's size " + format(size) + " m)");
  if (!same) ++out.differences;
  return Ok{};
}

}  // namespace

Result<RunComparison> compareRuns(const std::string& run_directory,
                                  const std::string& reference_directory,
                                  const ComparisonTolerance& tolerance) {
  Result<nlohmann::json> run = readSummary(run_directory);
  if (!run) return run.error();
  Result<nlohmann::json> reference = readSummary(reference_directory);
  if (!reference) return reference.error();
  RunComparison out;
  compareSummaries(run.value(), reference.value(), tolerance, out);
  for (const char* csv : {"wrench.csv", "energy.csv", "rigid.csv"}) {
    if (Status s = compareCsv(csv, run_directory, reference_directory, tolerance, out); !s)
      return s.error();
  }
  if (reference.value().contains("bodies") && reference.value()["bodies"].is_array()) {
    for (const nlohmann::json& body : reference.value()["bodies"]) {
      if (!body.contains("name") || !body["name"].is_string()) continue;
      const std::string name = body["name"].get<std::string>() + ".vtk";
      if (fs::path(name).has_parent_path()) continue;  // a file of this directory only
      if (!fs::exists(fs::path(reference_directory) / name)) continue;
      if (Status s = compareVtk(name, run_directory, reference_directory, tolerance, out); !s)
        return s.error();
    }
  }
  return out;
}

}  // namespace torsion::cli
