#pragma once
// The reference peer of the network device: what a vendor's driver process does, with a
// scripted trajectory in place of the arm. Each tick it sends one pose packet to the simulation
// and takes every wrench packet that arrived (newest wins). Used by the torsion_haptic_peer
// program and by the loopback tests. With a key it signs its poses (packet_key.h) under a fresh
// random session id and takes only signed wrenches of that session.

#include <cstdint>
#include <memory>
#include <optional>

#include "torsion/device/packet_stats.h"
#include "torsion/device/trajectory.h"
#include "torsion/device/udp_socket.h"

namespace torsion::device {

class NetworkPeer {
 public:
  /// Binds an ephemeral loopback port and sends to `simulation`; signs with `key` when given.
  static Loaded<std::unique_ptr<NetworkPeer>> open(const UdpEndpoint& simulation,
                                                   Trajectory trajectory,
                                                   std::optional<PacketKey> key = {});

  /// Sends the trajectory's pose and buttons at `time` (s since the peer started), flagged
  /// alive; then drains incoming wrenches.
  void tick(double time);
  /// Sends raw bytes to the simulation (tests use it to inject bad packets).
  void sendRaw(const void* bytes, std::size_t size);
  /// Ends the session: a last pose packet, not alive, with the goodbye flag (network_device.h).
  void sayGoodbye(double time);
  /// Sends a pose packet with an explicit sequence number (tests: duplicates, reordering).
  void sendPose(std::uint32_t sequence, const Pose& pose, std::uint32_t buttons, bool alive,
                bool goodbye = false);

  const Wrench& newestWrench() const { return newest_.wrench; }
  std::uint32_t newestEcho() const { return newest_.echo_sequence; }
  const PacketStats& stats() const { return stats_; }
  UdpEndpoint local() const { return socket_->local(); }
  const Trajectory& trajectory() const { return trajectory_; }
  std::uint64_t session() const { return session_; }

 private:
  NetworkPeer(std::shared_ptr<UdpSocket> socket, UdpEndpoint simulation, Trajectory trajectory,
              std::optional<PacketKey> key);
  const PacketKey* key() const { return key_ ? &*key_ : nullptr; }
  std::uint32_t nextSequence();
  void drain();

  std::shared_ptr<UdpSocket> socket_;
  UdpEndpoint simulation_;
  Trajectory trajectory_;
  std::optional<PacketKey> key_;
  std::uint64_t session_ = 0;  // signed: this peer's session id
  PacketFilter filter_{PacketKind::kWrench, key()};
  PacketStats stats_;
  Packet newest_;
  std::uint32_t sequence_ = 0;
};

}  // namespace torsion::device
