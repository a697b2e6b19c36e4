#pragma once
// A device in another process, over UDP (loopback by default): pose packets in, wrench packets
// out, in the format of udp_packet.h. A vendor's force-feedback driver (their SDKs are
// proprietary) runs as its own process and speaks this format; network_peer.h is the reference
// peer. It is alive while accepted packets flagged alive keep arriving within `timeout`.
//
// Session: the first peer (address and port) whose valid pose arrives is bound; datagrams from
// any other address are dropped and counted (PacketStats::foreign) until the session ends, either
// by the peer's goodbye (a pose packet with flags bit 1; the device answers with a zero wrench) or
// after `session_timeout` without an accepted pose from it. Then the next peer may bind.
//
// Authentication (packet_key.h): with a key, only signed packets whose MAC verifies count, and a
// session is also its peer's random session id: a session id that has ended is never accepted
// again, so a recorded session cannot be replayed once it is over. Without a key, only
// unauthenticated (version 1) packets are accepted, as before.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "torsion/device/haptic_device.h"
#include "torsion/device/packet_stats.h"
#include "torsion/device/udp_socket.h"

namespace torsion::device {

struct NetworkDeviceSettings {
  UdpEndpoint local{0x7f000001, 5750};  ///< where poses arrive; port 0: any free port
  double timeout = 0.05;                ///< s without an accepted pose before the device is dead
  double session_timeout = 1.0;         ///< s without an accepted pose before another peer may bind
  DeviceLimits limits;                  ///< of the device behind the peer
  std::optional<PacketKey> key;         ///< shared with the peer; empty: unauthenticated packets
};

class NetworkDevice : public HapticDevice {
 public:
  static Loaded<std::unique_ptr<NetworkDevice>> open(const NetworkDeviceSettings& settings);
  /// Sends a zero wrench to the peer before the socket closes, whatever ended the session.
  ~NetworkDevice() override;

  std::string name() const override;
  DeviceLimits limits() const override { return settings_.limits; }
  /// Drains every queued datagram, keeps the newest valid pose of the session's peer.
  DeviceSample read(double time) override;
  /// Sends the wrench to the session's peer (nothing while no peer is bound).
  void write(const Wrench& wrench) override;

  UdpEndpoint local() const { return socket_->local(); }
  const PacketStats& stats() const { return stats_; }
  /// True when the device has a key: only signed packets are heard.
  bool authenticated() const { return settings_.key.has_value(); }

 private:
  NetworkDevice(const NetworkDeviceSettings& settings, std::shared_ptr<UdpSocket> socket);
  const PacketKey* key() const { return settings_.key ? &*settings_.key : nullptr; }
  void endSession();
  /// Signed packets: false (and counted) when `packet` belongs to a session that has ended.
  bool freshSession(const Packet& packet);

  NetworkDeviceSettings settings_;
  std::shared_ptr<UdpSocket> socket_;
  PacketFilter filter_{PacketKind::kPose, key()};
  PacketStats stats_;
  Packet newest_;
  bool have_peer_ = false;
  UdpEndpoint peer_;
  std::uint64_t session_ = 0;                  // signed: the bound session's id
  std::vector<std::uint64_t> ended_sessions_;  // signed: ids never to be accepted again
  double last_accepted_time_ = -1e300;         // loop clock, s
  std::uint32_t sent_sequence_ = 0;
};

}  // namespace torsion::device
