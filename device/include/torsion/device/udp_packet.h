#pragma once
// The network device's wire format (docs/haptic-devices.md, "Packet format"). One UDP datagram is
// one packet, little-endian. Version 1 (unauthenticated) is exactly kPacketSize bytes:
//
//   offset size  field
//   0      4     magic 0x54525348 ("HSRT" in memory; reads "TRSH" as a big-endian word)
//   4      2     version = 1 (unauthenticated) or 3 (signed)
//   6      2     kind: 1 = pose (peer -> simulation), 2 = wrench (simulation -> peer)
//   8      4     sequence number, +1 per packet sent by that side (wraps modulo 2^32)
//   12     4     flags: bit 0 alive (pose) / force enabled (wrench);
//                bit 1 goodbye (pose): the peer's last packet, it ends the session
//   16     8     timestamp, ns, sender's monotonic clock
//   24     56    pose:   7 float64 px py pz (m) qw qx qy qz (unit quaternion)
//                wrench: 6 float64 fx fy fz (N) tx ty tz (N m), then 8 bytes zero
//   80     4     pose: buttons (bit k = button k+1); wrench: sequence of the newest pose received
//   84     4     reserved, zero
//   88     4     checksum: FNV-1a 32 of bytes 0..87
//
// Version 3 (signed, packet_key.h) is exactly kSignedPacketSize bytes: bytes 0..87 as above, then
//   88     8     peer nonce: random, chosen by the peer for each session; wrenches echo it
//   96     8     device nonce: random, chosen by the device for each session (its challenge);
//                0 in the peer's hello, before it has one
//   104    32    HMAC-SHA256 of bytes 0..103 under the shared key
// A signed session is bound to both nonces, fresh from the CSPRNG: the device takes a pose only
// when it carries the nonce the device issued for the current session, so packets recorded in
// any earlier session (of this run or another) never verify as current. Within a session the
// sequence numbers only increase (no wrap-around), so a packet cannot be replayed inside it.
// Version 2 (signed, 128 bytes: a peer nonce only) is no longer accepted: such datagrams are
// recognised and counted as PacketError::kOldVersion.
//
// decodePacket classifies what arrives; NetworkDevice counts every kind of rejection.

#include <array>
#include <cstddef>
#include <cstdint>

#include "torsion/device/device_types.h"
#include "torsion/device/packet_key.h"

namespace torsion::device {

inline constexpr std::size_t kPacketSize = 92;
inline constexpr std::uint32_t kPacketMagic = 0x54525348;
inline constexpr std::uint16_t kPacketVersion = 1;
inline constexpr std::size_t kSignedPacketSize = 136;
inline constexpr std::uint16_t kSignedPacketVersion = 3;
/// The earlier signed version (a peer nonce only): recognised to be refused as such.
inline constexpr std::size_t kOldSignedPacketSize = 128;
inline constexpr std::uint16_t kOldSignedPacketVersion = 2;
/// The longest datagram either version can be (receive buffers hold one more byte, to tell
/// longer datagrams apart).
inline constexpr std::size_t kMaxPacketSize = kSignedPacketSize;

enum class PacketKind : std::uint16_t { kPose = 1, kWrench = 2 };

struct Packet {
  PacketKind kind = PacketKind::kPose;
  std::uint32_t sequence = 0;
  bool flag = false;     ///< pose: device alive; wrench: force enabled
  bool goodbye = false;  ///< pose: the peer ends its session with this packet (flags bit 1)
  std::uint64_t timestamp_ns = 0;
  Pose pose;                        ///< kind pose
  Wrench wrench;                    ///< kind wrench
  std::uint32_t buttons = 0;        ///< kind pose
  std::uint32_t echo_sequence = 0;  ///< kind wrench
  std::uint64_t session = 0;        ///< signed packets: the peer's nonce (0: unsigned)
  std::uint64_t device_nonce = 0;   ///< signed packets: the device's nonce (0: a peer's hello)
};

enum class PacketError {
  kNone,
  kTruncated,  ///< not the size of either version
  kMalformed,  ///< bad magic, version, kind or checksum; non-finite numbers; not a unit quaternion
  /// With a key: not signed, or a MAC that does not verify. Without one: a signed packet (it
  /// cannot be checked; the sender has a key this side lacks).
  kUnauthenticated,
  /// A signed packet of the earlier version 2 (magic, version and size match): its sender must
  /// be updated to version 3.
  kOldVersion,
};

using PacketBytes = std::array<unsigned char, kPacketSize>;
using SignedPacketBytes = std::array<unsigned char, kSignedPacketSize>;

/// Version 1, unauthenticated.
PacketBytes encodePacket(const Packet& packet);
/// Version 3: `packet.session`, `packet.device_nonce` and the MAC under `key`.
SignedPacketBytes encodeSignedPacket(const Packet& packet, const PacketKey& key);
/// Decodes `size` bytes; `out` is only meaningful when the result is kNone. Without a key only
/// version 1 is accepted; with one, only version 3 packets whose MAC verifies.
PacketError decodePacket(const unsigned char* bytes, std::size_t size, Packet& out,
                         const PacketKey* key = nullptr);

/// Serial-number order of sequence numbers (RFC 1982): true when b comes after a.
inline bool sequenceAfter(std::uint32_t b, std::uint32_t a) {
  return static_cast<std::int32_t>(b - a) > 0;
}

}  // namespace torsion::device
