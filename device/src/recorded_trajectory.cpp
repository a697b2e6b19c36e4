// Replay: a haptic loop log (CSV with a header naming its columns) read back as a Trajectory.
// Only the columns time, px, py, pz, qw, qx, qy, qz and buttons are used, found by name, so logs
// with extra columns (or in another order) replay too.
#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

#include "torsion/device/pose_math.h"
#include "torsion/device/scripted_device.h"

namespace torsion::device {

namespace {

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream stream(line);
  std::string cell;
  while (std::getline(stream, cell, ','))
    cells.push_back(cell);
  return cells;
}

bool parseNumber(const std::string& text, double& out) {
  char* end = nullptr;
  out = std::strtod(text.c_str(), &end);
  return end != text.c_str() && *end == '\0' && std::isfinite(out);
}

}  // namespace

Loaded<Trajectory> loadRecordedTrajectory(const std::string& csv_path) {
  using Out = Loaded<Trajectory>;
  std::ifstream in(csv_path);
  if (!in) return Out::fail(csv_path + ": cannot open the recorded log");
  std::string line;
  if (!std::getline(in, line)) return Out::fail(csv_path + ":1: empty file, expected a header");
  const std::vector<std::string> header = splitCsv(line);
  const char* names[] = {"time", "px", "py", "pz", "qw", "qx", "qy", "qz", "buttons"};
  size_t column[9];
  for (int k = 0; k < 9; ++k) {
    column[k] = header.size();
    for (size_t c = 0; c < header.size(); ++c) {
      if (header[c] == names[k]) column[k] = c;
    }
    if (column[k] == header.size()) {
      return Out::fail(csv_path + ":1: the header has no column '" + names[k] + "'");
    }
  }
  std::vector<TrajectoryKeyframe> frames;
  std::vector<ButtonEvent> buttons;
  double t0 = 0;
  for (int line_number = 2; std::getline(in, line); ++line_number) {
    if (line.empty()) continue;
    const std::vector<std::string> cells = splitCsv(line);
    double v[9];
    for (int k = 0; k < 9; ++k) {
      if (column[k] >= cells.size() || !parseNumber(cells[column[k]], v[k])) {
        return Out::fail(csv_path + ":" + std::to_string(line_number) + ": column '" + names[k] +
                         "' is missing or not a finite number");
      }
    }
    if (frames.empty()) t0 = v[0];
    const double t = v[0] - t0;
    if (!frames.empty() && !(t > frames.back().time)) continue;  // repeated time stamps: keep one
    Pose pose{{v[1], v[2], v[3]}, normalized({v[4], v[5], v[6], v[7]})};
    frames.push_back({t, pose});
    const auto held = static_cast<std::uint32_t>(v[8]);
    if (buttons.empty() || buttons.back().held != held) buttons.push_back({t, held});
  }
  if (frames.empty()) return Out::fail(csv_path + ": no samples after the header");
  return Out{Trajectory(std::move(frames), std::move(buttons)), {}};
}

}  // namespace torsion::device
