// Trajectory files (JSON, docs/haptic-devices.md, "Device kinds"):
//   {"start": {"position": [x, y, z], "rotation": [rx, ry, rz]},        optional, default zero
//    "segments": [{"duration": s, "linear_velocity": [..], "angular_velocity": [..]}, ...]
//      or "keyframes": [{"time": s, "position": [..], "rotation": [..]}, ...],
//    "buttons": [{"time": s, "held": [1]}, ...]}                        optional
// Rotations are rotation vectors (axis * angle, rad) in the device frame.
#include <cmath>
#include <nlohmann/json.hpp>

#include "torsion/device/file_io.h"
#include "torsion/device/json_check.h"
#include "torsion/device/pose_math.h"
#include "torsion/device/trajectory.h"

namespace torsion::device {

namespace {

using json = nlohmann::json;

// Thrown inside this file only, turned into a Loaded error at the boundary.
struct BadKey {
  std::string message;
};

const json& member(const json& object, const std::string& key, const std::string& where) {
  if (!object.is_object()) throw BadKey{"key '" + where + "': expected an object"};
  auto it = object.find(key);
  if (it == object.end()) throw BadKey{"key '" + where + key + "': missing"};
  return *it;
}

double number(const json& value, const std::string& where) {
  if (!value.is_number()) throw BadKey{"key '" + where + "': expected a number"};
  const double v = value.get<double>();
  if (!std::isfinite(v)) throw BadKey{"key '" + where + "': not finite"};
  return v;
}

Vec3 vec3(const json& value, const std::string& where) {
  if (!value.is_array() || value.size() != 3) {
    throw BadKey{"key '" + where + "': expected an array of 3 numbers"};
  }
  return {number(value[0], where + "[0]"), number(value[1], where + "[1]"),
          number(value[2], where + "[2]")};
}

Vec3 optionalVec3(const json& object, const std::string& key, const std::string& where) {
  return object.contains(key) ? vec3(object[key], where + key) : Vec3{};
}

Pose pose(const json& object, const std::string& where) {
  Pose p;
  p.position = optionalVec3(object, "position", where);
  p.orientation = fromRotationVector(optionalVec3(object, "rotation", where));
  return p;
}

std::vector<TrajectoryKeyframe> keyframes(const json& list) {
  if (!list.is_array() || list.empty()) throw BadKey{"key 'keyframes': expected a non-empty array"};
  std::vector<TrajectoryKeyframe> out;
  for (size_t k = 0; k < list.size(); ++k) {
    const std::string where = "keyframes[" + std::to_string(k) + "].";
    TrajectoryKeyframe f;
    f.time = number(member(list[k], "time", where), where + "time");
    f.pose = pose(list[k], where);
    if (!out.empty() && !(f.time > out.back().time)) {
      throw BadKey{"key '" + where + "time': times must increase strictly"};
    }
    out.push_back(f);
  }
  return out;
}

std::vector<MotionSegment> segments(const json& list) {
  if (!list.is_array() || list.empty()) throw BadKey{"key 'segments': expected a non-empty array"};
  std::vector<MotionSegment> out;
  for (size_t k = 0; k < list.size(); ++k) {
    const std::string where = "segments[" + std::to_string(k) + "].";
    MotionSegment s;
    s.duration = number(member(list[k], "duration", where), where + "duration");
    if (!(s.duration > 0)) throw BadKey{"key '" + where + "duration': must be positive"};
    s.linear_velocity = optionalVec3(list[k], "linear_velocity", where);
    s.angular_velocity = optionalVec3(list[k], "angular_velocity", where);
    out.push_back(s);
  }
  return out;
}

std::vector<ButtonEvent> buttons(const json& list) {
  if (!list.is_array()) throw BadKey{"key 'buttons': expected an array"};
  std::vector<ButtonEvent> out;
  for (size_t k = 0; k < list.size(); ++k) {
    const std::string where = "buttons[" + std::to_string(k) + "].";
    ButtonEvent e;
    e.time = number(member(list[k], "time", where), where + "time");
    if (!out.empty() && e.time < out.back().time) {
      throw BadKey{"key '" + where + "time': times must not decrease"};
    }
    const json& held = member(list[k], "held", where);
    if (!held.is_array()) throw BadKey{"key '" + where + "held': expected an array of buttons"};
    for (const json& b : held) {
      if (!b.is_number_integer() || b.get<int>() < 1 || b.get<int>() > 32) {
        throw BadKey{"key '" + where + "held': buttons are numbered 1 to 32"};
      }
      e.held |= 1u << (b.get<int>() - 1);
    }
    out.push_back(e);
  }
  return out;
}

}  // namespace

Loaded<Trajectory> parseTrajectory(const std::string& json_text, const std::string& source) {
  // A strict pass first: duplicate keys, numbers beyond a double and syntax, with a position.
  if (const auto fault = findJsonTextFault(json_text)) {
    const std::string where =
        fault->line > 0 ? ":" + std::to_string(fault->line) + ":" + std::to_string(fault->column)
                        : std::string();
    return Loaded<Trajectory>::fail(source + where + ": not valid JSON: " + fault->what);
  }
  const json root = json::parse(json_text);
  try {
    if (!root.is_object()) throw BadKey{"top level: expected an object"};
    if (root.contains("segments") == root.contains("keyframes")) {
      throw BadKey{"keys 'segments' / 'keyframes': give exactly one of them"};
    }
    std::vector<TrajectoryKeyframe> frames;
    if (root.contains("keyframes")) {
      frames = keyframes(root["keyframes"]);
    } else {
      const Pose start = root.contains("start") ? pose(root["start"], "start.") : Pose{};
      frames = keyframesFromSegments(start, segments(root["segments"]));
    }
    std::vector<ButtonEvent> events =
        root.contains("buttons") ? buttons(root["buttons"]) : std::vector<ButtonEvent>{};
    return Loaded<Trajectory>{Trajectory(std::move(frames), std::move(events)), {}};
  } catch (const BadKey& e) {
    return Loaded<Trajectory>::fail(source + ": " + e.message);
  }
}

Loaded<Trajectory> loadTrajectory(const std::string& path) {
  std::string text;
  if (std::string error = readRegularFile(path, text); !error.empty())
    return Loaded<Trajectory>::fail(error);
  return parseTrajectory(text, path);
}

}  // namespace torsion::device
