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

#include <memory>
#include <string>

#include "torsion/device/haptic_device.h"
#include "torsion/device/packet_stats.h"
#include "torsion/device/udp_socket.h"

namespace torsion::device {

struct NetworkDeviceSettings {
  UdpEndpoint local{0x7f000001, 5750};  ///< where poses arrive; port 0: any free port
  double timeout = 0.05;                ///< s without an accepted pose before the device is dead
  double session_timeout = 1.0;         ///< s without an accepted pose before another peer may bind
  DeviceLimits limits;                  ///< of the device behind the peer
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

 private:
  NetworkDevice(const NetworkDeviceSettings& settings, std::shared_ptr<UdpSocket> socket);
  void endSession();

  NetworkDeviceSettings settings_;
  std::shared_ptr<UdpSocket> socket_;
  PacketFilter filter_{PacketKind::kPose};
  PacketStats stats_;
  Packet newest_;
  bool have_peer_ = false;
  UdpEndpoint peer_;
  double last_accepted_time_ = -1e300;  // loop clock, s
  std::uint32_t sent_sequence_ = 0;
};

}  // namespace torsion::device
