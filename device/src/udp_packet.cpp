#include "torsion/device/udp_packet.h"

#include <cmath>
#include <cstring>

namespace torsion::device {

namespace {

std::uint32_t fnv1a(const unsigned char* bytes, std::size_t n) {
  std::uint32_t h = 2166136261u;
  for (std::size_t k = 0; k < n; ++k) {
    h ^= bytes[k];
    h *= 16777619u;
  }
  return h;
}

// Explicit little-endian byte order, whatever the host's.
template <class U>
void put(unsigned char* at, U value) {
  for (std::size_t k = 0; k < sizeof(U); ++k)
    at[k] = static_cast<unsigned char>(value >> (8 * k));
}
template <class U>
U get(const unsigned char* at) {
  U value = 0;
  for (std::size_t k = 0; k < sizeof(U); ++k)
    value |= static_cast<U>(at[k]) << (8 * k);
  return value;
}
void putDouble(unsigned char* at, double value) {
  std::uint64_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  put(at, bits);
}
double getDouble(const unsigned char* at) {
  const auto bits = get<std::uint64_t>(at);
  double value;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}

// Bytes 0..87, shared by both versions.
void encodeBody(const Packet& packet, std::uint16_t version, unsigned char* b) {
  put(&b[0], kPacketMagic);
  put(&b[4], version);
  put(&b[6], static_cast<std::uint16_t>(packet.kind));
  put(&b[8], packet.sequence);
  put(&b[12], static_cast<std::uint32_t>((packet.flag ? 1u : 0u) | (packet.goodbye ? 2u : 0u)));
  put(&b[16], packet.timestamp_ns);
  double values[7] = {};
  if (packet.kind == PacketKind::kPose) {
    const Pose& p = packet.pose;
    const double v[7] = {p.position.x,    p.position.y,    p.position.z,   p.orientation.w,
                         p.orientation.x, p.orientation.y, p.orientation.z};
    std::memcpy(values, v, sizeof v);
    put(&b[80], packet.buttons);
  } else {
    const Wrench& w = packet.wrench;
    const double v[6] = {w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z};
    std::memcpy(values, v, sizeof v);
    put(&b[80], packet.echo_sequence);
  }
  for (int k = 0; k < 7; ++k)
    putDouble(&b[24 + 8 * k], values[k]);
}

PacketError decodeBody(const unsigned char* bytes, Packet& out) {
  const auto kind = get<std::uint16_t>(bytes + 6);
  if (kind != 1 && kind != 2) return PacketError::kMalformed;
  out = Packet{};
  out.kind = static_cast<PacketKind>(kind);
  out.sequence = get<std::uint32_t>(bytes + 8);
  out.flag = (get<std::uint32_t>(bytes + 12) & 1u) != 0;
  out.goodbye = (get<std::uint32_t>(bytes + 12) & 2u) != 0;
  out.timestamp_ns = get<std::uint64_t>(bytes + 16);
  double v[7];
  for (int k = 0; k < 7; ++k) {
    v[k] = getDouble(bytes + 24 + 8 * k);
    if (!std::isfinite(v[k])) return PacketError::kMalformed;
  }
  if (out.kind == PacketKind::kPose) {
    out.pose = {{v[0], v[1], v[2]}, {v[3], v[4], v[5], v[6]}};
    const double q2 = v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6];
    if (std::abs(q2 - 1) > 1e-6) return PacketError::kMalformed;
    out.buttons = get<std::uint32_t>(bytes + 80);
  } else {
    out.wrench = {{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
    out.echo_sequence = get<std::uint32_t>(bytes + 80);
  }
  return PacketError::kNone;
}

}  // namespace

PacketBytes encodePacket(const Packet& packet) {
  PacketBytes b{};
  encodeBody(packet, kPacketVersion, b.data());
  put(&b[88], fnv1a(b.data(), 88));
  return b;
}

SignedPacketBytes encodeSignedPacket(const Packet& packet, const PacketKey& key) {
  SignedPacketBytes b{};
  encodeBody(packet, kSignedPacketVersion, b.data());
  put(&b[88], packet.session);
  put(&b[96], packet.device_nonce);
  const Mac mac = key.mac(b.data(), 104);
  std::memcpy(&b[104], mac.data(), mac.size());
  return b;
}

PacketError decodePacket(const unsigned char* bytes, std::size_t size, Packet& out,
                         const PacketKey* key) {
  if (size == kOldSignedPacketSize && get<std::uint32_t>(bytes) == kPacketMagic &&
      get<std::uint16_t>(bytes + 4) == kOldSignedPacketVersion)
    return PacketError::kOldVersion;
  if (size != kPacketSize && size != kSignedPacketSize) return PacketError::kTruncated;
  if (get<std::uint32_t>(bytes) != kPacketMagic) return PacketError::kMalformed;
  const auto version = get<std::uint16_t>(bytes + 4);
  if (version == kPacketVersion && size == kPacketSize) {
    if (get<std::uint32_t>(bytes + 88) != fnv1a(bytes, 88)) return PacketError::kMalformed;
    if (key) return PacketError::kUnauthenticated;  // well-formed, but anyone could have sent it
    return decodeBody(bytes, out);
  }
  if (version == kSignedPacketVersion && size == kSignedPacketSize) {
    // The MAC first: nothing of an unauthenticated packet is looked at further.
    if (!key || !key->verify(bytes + 104, bytes, 104)) return PacketError::kUnauthenticated;
    const PacketError error = decodeBody(bytes, out);
    out.session = get<std::uint64_t>(bytes + 88);
    out.device_nonce = get<std::uint64_t>(bytes + 96);
    return error;
  }
  return PacketError::kMalformed;
}

}  // namespace torsion::device
