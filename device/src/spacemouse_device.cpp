// The SpaceMouse device on libspnav (built only when libspnav is found; spacemouse_unavailable.cpp
// otherwise). Reads are non-blocking: every queued event is drained each tick, the newest motion
// reading is held and integrated.
#include "torsion/device/spacemouse_device.h"

#include <poll.h>
#include <spnav.h>

#include <atomic>

namespace torsion::device {

namespace {

std::atomic<bool> g_open{false};  // libspnav has one connection per process

class SpaceMouseDevice : public HapticDevice {
 public:
  explicit SpaceMouseDevice(const SpaceMouseSettings& settings)
      : settings_(settings), integrator_(settings) {}
  ~SpaceMouseDevice() override {
    spnav_close();
    g_open = false;
  }

  std::string name() const override { return "spacemouse(spacenavd)"; }

  DeviceLimits limits() const override {
    DeviceLimits l;  // no motors: zero force and torque
    l.workspace_min = settings_.workspace_min;
    l.workspace_max = settings_.workspace_max;
    return l;
  }

  DeviceSample read(double time) override {
    spnav_event event;
    while (alive_ && spnav_poll_event(&event) > 0) {
      if (event.type == SPNAV_EVENT_MOTION) {
        SpaceMouseReading r;
        r.translation[0] = event.motion.x;
        r.translation[1] = event.motion.y;
        r.translation[2] = event.motion.z;
        r.rotation[0] = event.motion.rx;
        r.rotation[1] = event.motion.ry;
        r.rotation[2] = event.motion.rz;
        integrator_.setReading(r);
      } else if (event.type == SPNAV_EVENT_BUTTON && event.button.bnum >= 0 &&
                 event.button.bnum < 32) {
        const std::uint32_t bit = 1u << event.button.bnum;
        buttons_ = event.button.press ? buttons_ | bit : buttons_ & ~bit;
      }
    }
    // A daemon that went away hangs up the socket: the device is dead from then on.
    pollfd p{spnav_fd(), POLLIN, 0};
    if (p.fd < 0 || (poll(&p, 1, 0) > 0 && (p.revents & (POLLHUP | POLLERR | POLLNVAL)))) {
      alive_ = false;
    }
    if (!alive_) integrator_.setReading({});
    DeviceSample sample;
    sample.time = time;
    sample.pose = integrator_.advance(time);
    sample.buttons = buttons_;
    sample.alive = alive_;
    return sample;
  }

  void write(const Wrench&) override {}  // no force output

 private:
  SpaceMouseSettings settings_;
  SpaceMouseIntegrator integrator_;
  std::uint32_t buttons_ = 0;
  bool alive_ = true;
};

}  // namespace

bool spaceMouseSupported() {
  return true;
}

Loaded<std::unique_ptr<HapticDevice>> openSpaceMouse(const SpaceMouseSettings& settings) {
  using Result = Loaded<std::unique_ptr<HapticDevice>>;
  const std::string invalid = settings.validate();
  if (!invalid.empty()) return Result::fail("SpaceMouse: " + invalid);
  if (g_open.exchange(true)) {
    return Result::fail("SpaceMouse: already open (libspnav allows one per process)");
  }
  if (spnav_open() == -1) {
    g_open = false;
    return Result::fail(
        "SpaceMouse: cannot connect to the spacenavd daemon (no daemon is running, or its socket "
        "/var/run/spnav.sock is missing): install and start it (Debian package spacenavd, "
        "`systemctl start spacenavd`) with the SpaceMouse plugged in");
  }
  return Result{std::unique_ptr<HapticDevice>(new SpaceMouseDevice(settings)), {}};
}

}  // namespace torsion::device
