#pragma once
// A device that plays a Trajectory (a scripted file, or a recorded log for replay) from the
// first time it is read. It has no motors: written wrenches are only kept for inspection. Tests
// can make it die at a set time to exercise the safety rules.

#include <limits>
#include <string>

#include "torsion/device/haptic_device.h"
#include "torsion/device/trajectory.h"

namespace torsion::device {

class ScriptedDevice : public HapticDevice {
 public:
  ScriptedDevice(Trajectory trajectory, DeviceLimits limits, std::string name);

  std::string name() const override { return name_; }
  DeviceLimits limits() const override { return limits_; }
  DeviceSample read(double time) override;
  void write(const Wrench& wrench) override;

  /// From this trajectory time on the device reports itself dead and holds its last pose.
  void dieAt(double trajectory_time) { death_time_ = trajectory_time; }
  /// True once the whole trajectory has been played.
  bool finished(double time) const;
  const Wrench& lastWritten() const { return last_written_; }
  long writes() const { return writes_; }

 private:
  Trajectory trajectory_;
  DeviceLimits limits_;
  std::string name_;
  double start_time_ = std::numeric_limits<double>::quiet_NaN();  // loop time of the first read
  double death_time_ = std::numeric_limits<double>::infinity();
  Wrench last_written_;
  long writes_ = 0;
};

/// Limits of a typical desktop 6-DoF force-feedback arm (the report's Virtuose 6D class):
/// 30 N, 3 N m, a 0.4 m cube of workspace around the origin.
DeviceLimits defaultDeviceLimits();

/// A trajectory from a haptic loop log (HapticLoop::writeLog, 1 kHz CSV): its time, pose and
/// buttons columns, times shifted to start at 0. Errors name the file and line.
Loaded<Trajectory> loadRecordedTrajectory(const std::string& csv_path);

}  // namespace torsion::device
