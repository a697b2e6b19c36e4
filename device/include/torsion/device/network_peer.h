#pragma once
// The reference peer of the network device: what a vendor's driver process does, with a
// scripted trajectory in place of the arm. Each tick it sends one pose packet to the simulation
// and takes every wrench packet that arrived (newest wins). Used by the torsion_haptic_peer
// program and by the loopback tests. With a key it signs its poses (packet_key.h): each session
// starts with a fresh random peer nonce and hellos (poses whose device nonce is 0, which the
// device does not take) until the device's challenge brings the device nonce; from then on its
// poses carry both nonces, and it takes only signed wrenches carrying both (a newer challenge of
// the device for the same session replaces the device nonce; an earlier one never comes back).
// After its goodbye, the next tick starts a new session. What it renders goes through
// a WrenchWatchdog (wrench_watchdog.h): when wrenches stop arriving (the simulation was killed,
// stopped or hung) the rendered wrench fades to zero, as the haptic loop's output on a stall.

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "torsion/device/packet_stats.h"
#include "torsion/device/trajectory.h"
#include "torsion/device/udp_socket.h"
#include "torsion/device/wrench_watchdog.h"

namespace torsion::device {

class NetworkPeer {
 public:
  /// Binds an ephemeral loopback port and sends to `simulation`; signs with `key` when given.
  /// `limits`: the device behind the peer's (what it renders is saturated to them, and the
  /// watchdog's fade runs at limit / fade_time).
  static Loaded<std::unique_ptr<NetworkPeer>> open(const UdpEndpoint& simulation,
                                                   Trajectory trajectory,
                                                   std::optional<PacketKey> key = {},
                                                   const DeviceLimits& limits = peerLimits(),
                                                   const WatchdogSettings& watchdog = {});
  /// The desktop arm's 30 N, 3 N m (scripted_device.h's defaultDeviceLimits()).
  static DeviceLimits peerLimits();

  /// Sends the trajectory's pose and buttons at `time` (s since the peer started), flagged
  /// alive; then drains incoming wrenches and updates the rendered wrench.
  void tick(double time);
  /// Sends raw bytes to the simulation (tests use it to inject bad packets).
  void sendRaw(const void* bytes, std::size_t size);
  /// Ends the session: a last pose packet, not alive, with the goodbye flag (network_device.h).
  /// Signed: the next packet opens a new session (fresh peer nonce, a hello).
  void sayGoodbye(double time);
  /// Sends a pose packet with an explicit sequence number (tests: duplicates, reordering).
  void sendPose(std::uint32_t sequence, const Pose& pose, std::uint32_t buttons, bool alive,
                bool goodbye = false);

  /// The newest wrench received, as it came.
  const Wrench& newestWrench() const { return newest_.wrench; }
  /// What the device behind the peer renders after the last tick(): the newest wrench while
  /// wrenches keep arriving, fading to zero when they stop.
  const Wrench& renderedWrench() const { return rendered_; }
  std::uint32_t newestEcho() const { return newest_.echo_sequence; }
  const PacketStats& stats() const { return stats_; }
  UdpEndpoint local() const { return socket_->local(); }
  const Trajectory& trajectory() const { return trajectory_; }
  /// Signed: this session's peer nonce, and the device nonce (0 until the device's challenge).
  std::uint64_t session() const { return session_; }
  std::uint64_t deviceNonce() const { return device_nonce_; }

 private:
  NetworkPeer(std::shared_ptr<UdpSocket> socket, UdpEndpoint simulation, Trajectory trajectory,
              std::optional<PacketKey> key, const DeviceLimits& limits,
              const WatchdogSettings& watchdog);
  const PacketKey* key() const { return key_ ? &*key_ : nullptr; }
  std::uint32_t nextSequence();
  /// Signed: a fresh peer nonce, no device nonce yet; sequences and wrench order start afresh.
  void newSession();
  /// Signed: true when `packet` carries this session's nonces, adopting the device nonce of a
  /// challenge; counts it otherwise.
  bool inSession(const Packet& packet);
  /// Takes every wrench that arrived; `time`: when, for the watchdog.
  void drain(double time);

  std::shared_ptr<UdpSocket> socket_;
  UdpEndpoint simulation_;
  Trajectory trajectory_;
  std::optional<PacketKey> key_;
  std::uint64_t session_ = 0;           // signed: this session's peer nonce
  std::uint64_t device_nonce_ = 0;      // signed: the device's, from its challenge (0: none yet)
  std::uint64_t ended_session_ = 0;     // signed: the previous session's peer nonce
  std::vector<std::uint64_t> retired_;  // signed: device nonces of this session replaced since
  PacketFilter filter_{PacketKind::kWrench, key()};
  PacketStats stats_;
  Packet newest_;
  WrenchWatchdog watchdog_;
  Wrench rendered_;
  std::uint32_t sequence_ = 0;
};

}  // namespace torsion::device
