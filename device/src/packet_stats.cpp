#include "torsion/device/packet_stats.h"

namespace torsion::device {

bool PacketFilter::accept(const unsigned char* bytes, std::size_t size, Packet& out,
                          PacketStats& stats) {
  const PacketError error = decodePacket(bytes, size, out);
  if (error == PacketError::kTruncated) {
    ++stats.truncated;
    return false;
  }
  if (error != PacketError::kNone || out.kind != expected_) {
    ++stats.malformed;
    return false;
  }
  if (any_) {
    if (out.sequence == newest_) {
      ++stats.duplicate;
      return false;
    }
    if (!sequenceAfter(out.sequence, newest_)) {
      ++stats.out_of_order;
      return false;
    }
    stats.lost += out.sequence - newest_ - 1;
  }
  any_ = true;
  newest_ = out.sequence;
  ++stats.accepted;
  return true;
}

}  // namespace torsion::device
