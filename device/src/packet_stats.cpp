#include "torsion/device/packet_stats.h"

namespace torsion::device {

bool PacketFilter::accept(const unsigned char* bytes, std::size_t size, Packet& out,
                          PacketStats& stats) {
  return decode(bytes, size, out, stats) && inOrder(out, stats);
}

bool PacketFilter::decode(const unsigned char* bytes, std::size_t size, Packet& out,
                          PacketStats& stats) const {
  const PacketError error = decodePacket(bytes, size, out, key_);
  if (error == PacketError::kTruncated) {
    ++stats.truncated;
    return false;
  }
  if (error == PacketError::kOldVersion) {
    ++stats.old_version;
    return false;
  }
  if (error == PacketError::kUnauthenticated) {
    ++stats.unauthenticated;
    return false;
  }
  if (error != PacketError::kNone || out.kind != expected_) {
    ++stats.malformed;
    return false;
  }
  return true;
}

bool PacketFilter::inOrder(const Packet& packet, PacketStats& stats) {
  if (any_) {
    if (packet.sequence == newest_) {
      ++stats.duplicate;
      return false;
    }
    // A signed sequence never wraps: serial-number order would let a packet recorded 2^31
    // packets ago count as new.
    const bool after = key_ ? packet.sequence > newest_ : sequenceAfter(packet.sequence, newest_);
    if (!after) {
      ++stats.out_of_order;
      return false;
    }
    stats.lost += packet.sequence - newest_ - 1;
  }
  any_ = true;
  newest_ = packet.sequence;
  ++stats.accepted;
  return true;
}

}  // namespace torsion::device
