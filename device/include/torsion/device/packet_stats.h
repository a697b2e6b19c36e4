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
  std::atomic<std::uint64_t> sent{0};
  std::atomic<std::uint64_t> send_failed{0};

  std::uint64_t rejected() const {
    return truncated.load() + malformed.load() + out_of_order.load() + duplicate.load() +
           foreign.load();
  }
};

/// Filters a stream of datagrams of one expected kind: decodes, rejects and counts, and accepts
/// only packets newer than the newest accepted one.
class PacketFilter {
 public:
  explicit PacketFilter(PacketKind expected) : expected_(expected) {}
  /// True when the datagram is accepted (then `out` holds it).
  bool accept(const unsigned char* bytes, std::size_t size, Packet& out, PacketStats& stats);

 private:
  PacketKind expected_;
  bool any_ = false;
  std::uint32_t newest_ = 0;
};

}  // namespace torsion::device
