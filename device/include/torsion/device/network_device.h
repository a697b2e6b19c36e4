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
// session is bound to fresh randomness from both sides. A peer opens one with a hello (a signed
// pose whose device nonce is 0, never taken as a pose); the device answers with a challenge (a
// signed zero wrench, force off, echoing the peer's nonce and carrying a device nonce fresh from
// the CSPRNG), and only poses carrying both nonces bind and drive the session. A goodbye (or a
// timeout) retires the device nonce for good, so packets recorded in an earlier session, of this
// run or of another, are refused (`replayed`) and never take the hand. Without a key, only
// unauthenticated (version 1) packets are accepted.
//
// Cost per read: at most kMaxDatagramsPerRead datagrams are taken from the socket per read(), so a
// flood (valid or not) costs each tick a bounded time; the rest wait for the next reads.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "torsion/device/haptic_device.h"
#include "torsion/device/packet_stats.h"
#include "torsion/device/udp_socket.h"

namespace torsion::device {

/// Datagrams read() takes from the socket at most per call: a legitimate peer sends one per
/// tick; the margin absorbs bursts after a late tick. Each costs a receive and, signed, an HMAC
/// (about 2-4 us together), so a read costs at most about 0.25 ms however fast datagrams arrive.
inline constexpr int kMaxDatagramsPerRead = 64;

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
  /// Takes up to kMaxDatagramsPerRead queued datagrams, keeps the newest valid pose of the
  /// session's peer; answers signed hellos with a challenge.
  DeviceSample read(double time) override;
  /// Sends the wrench to the session's peer (nothing while no peer is bound).
  void write(const Wrench& wrench) override;

  UdpEndpoint local() const { return socket_->local(); }
  const PacketStats& stats() const { return stats_; }
  /// True when the device has a key: only signed packets are heard.
  bool authenticated() const { return settings_.key.has_value(); }
  /// Datagrams the last read() took from the socket (at most kMaxDatagramsPerRead).
  int lastReadDatagrams() const { return last_read_datagrams_; }

 private:
  NetworkDevice(const NetworkDeviceSettings& settings, std::shared_ptr<UdpSocket> socket);
  const PacketKey* key() const { return settings_.key ? &*settings_.key : nullptr; }
  void endSession();
  /// Signed packets: true when `packet` belongs to the current session, or answers the pending
  /// challenge (it then binds); otherwise a hello is answered with a challenge, and a packet of
  /// another session is counted as replayed (and challenged: its peer may have lost the session).
  bool inSession(const Packet& packet, const UdpEndpoint& from);
  /// Sends `to` a challenge for its peer nonce `session`: the same device nonce to the same
  /// hello, a fresh one otherwise.
  void challenge(std::uint64_t session, const UdpEndpoint& to);
  void send(Packet packet, const UdpEndpoint& to);

  NetworkDeviceSettings settings_;
  std::shared_ptr<UdpSocket> socket_;
  PacketFilter filter_{PacketKind::kPose, key()};
  PacketStats stats_;
  Packet newest_;
  bool have_peer_ = false;
  UdpEndpoint peer_;
  std::uint64_t session_ = 0;            // signed: the bound session's peer nonce
  std::uint64_t nonce_ = 0;              // signed: the bound session's device nonce
  bool challenged_ = false;              // signed: a challenge is pending
  UdpEndpoint challenge_to_;             // its peer,
  std::uint64_t challenge_session_ = 0;  // the peer nonce it answers,
  std::uint64_t challenge_nonce_ = 0;    // and the device nonce it carries
  double last_accepted_time_ = -1e300;   // loop clock, s
  std::uint32_t sent_sequence_ = 0;
  int last_read_datagrams_ = 0;
};

}  // namespace torsion::device
