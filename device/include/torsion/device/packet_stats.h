#pragma once
// Counts of what a network endpoint received, by fate. Written by the thread that receives,
// readable from any thread (relaxed atomics: these are statistics, not synchronisation).

#include <atomic>
#include <cstdint>

#include "torsion/device/udp_packet.h"

namespace torsion::device {

struct PacketStats {
  std::atomic<std::uint64_t> accepted{0};
  std::atomic<std::uint64_t> truncated{0};     ///< wrong length
  std::atomic<std::uint64_t> malformed{0};     ///< bad magic/version/kind/checksum/numbers
  std::atomic<std::uint64_t> out_of_order{0};  ///< older than the newest accepted
  std::atomic<std::uint64_t> duplicate{0};     ///< same sequence as the newest accepted
  std::atomic<std::uint64_t> lost{0};          ///< gaps in the sequence (sent but never seen)
  std::atomic<std::uint64_t> foreign{0};       ///< from another address than the session's peer
  /// With a key: unsigned, or a MAC that does not verify (wrong key, altered bytes). Without a
  /// key: signed packets, which cannot be checked.
  std::atomic<std::uint64_t> unauthenticated{0};
  std::atomic<std::uint64_t> replayed{0};  ///< signed, but of a session that is not the current one
  /// Signed in the earlier packet version 2 (a peer nonce only): the sender must be updated.
  std::atomic<std::uint64_t> old_version{0};
  std::atomic<std::uint64_t> sent{0};
  std::atomic<std::uint64_t> send_failed{0};

  std::uint64_t rejected() const {
    return truncated.load() + malformed.load() + out_of_order.load() + duplicate.load() +
           foreign.load() + unauthenticated.load() + replayed.load() + old_version.load();
  }
};

/// Filters a stream of datagrams of one expected kind: decodes (with `key`, only signed packets
/// whose MAC verifies), rejects and counts, and accepts only packets newer than the newest
/// accepted one. Signed packets' sequence numbers must increase without wrapping around.
class PacketFilter {
 public:
  explicit PacketFilter(PacketKind expected, const PacketKey* key = nullptr)
      : expected_(expected), key_(key) {}
  /// True when the datagram is accepted (then `out` holds it): decode() then inOrder().
  bool accept(const unsigned char* bytes, std::size_t size, Packet& out, PacketStats& stats);
  /// True when the datagram is a well-formed (and, with a key, authentic) packet of the
  /// expected kind; counts it otherwise.
  bool decode(const unsigned char* bytes, std::size_t size, Packet& out, PacketStats& stats) const;
  /// True when `packet` is newer than the newest one taken, which it then becomes; counts it
  /// otherwise.
  bool inOrder(const Packet& packet, PacketStats& stats);

 private:
  PacketKind expected_;
  const PacketKey* key_;
  bool any_ = false;
  std::uint32_t newest_ = 0;
};

}  // namespace torsion::device
