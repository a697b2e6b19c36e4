#include "device_options.h"

namespace torsion::cli {

void addDeviceOptions(CLI::App& command, scene::DeviceOverrides& into) {
  command.add_option("--device", into.devices,
                     "Drive a hand with a device instead of its script, or hold a dynamic "
                     "rigid body with one as a tool (repeatable): NAME=scripted:FILE, "
                     "NAME=replay:LOG.csv, NAME=network[:[HOST:]PORT], NAME=spacemouse, "
                     "NAME=plugin:LIBRARY[:CONFIG], or (torsion view, a tool) NAME=manual: "
                     "moved by the viewer's mouse and keys");
  command.add_option("--haptics", into.haptics,
                     "Haptic loops: lockstep (simulated clock, deterministic; default for "
                     "scripted and replay devices) or threaded (1 kHz threads, simulation paced "
                     "to wall-clock time; default for network and SpaceMouse)");
  command.add_option("--sim-priority", into.simulation_priority,
                     "Threaded haptics: run the simulation thread at this real-time (SCHED_FIFO) "
                     "priority, 1-79, below the loops' 80, so that on a loaded machine its steps "
                     "keep their pace and the wrench the device renders stays young; needs the "
                     "privilege (root or CAP_SYS_NICE: a warning says when it is refused); 0 "
                     "(default): unchanged");
  command.add_flag("--allow-remote-device", into.allow_remote_devices,
                   "Let a network device without a key listen on an address other than loopback "
                   "(its packets are not authenticated: anyone who can reach the port first "
                   "drives the hand; docs/haptic-devices.md tells how to give it a key)");
}

}  // namespace torsion::cli
