#include "torsion/device/udp_packet.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

namespace torsion::device {
namespace {

Packet posePacket() {
  Packet p;
  p.kind = PacketKind::kPose;
  p.sequence = 42;
  p.flag = true;
  p.timestamp_ns = 123456789012345ull;
  p.pose = {{0.1, -0.2, 0.3}, {std::sqrt(0.5), 0, std::sqrt(0.5), 0}};
  p.buttons = 3;
  return p;
}

TEST(UdpPacket, PoseAndWrenchRoundTripBitExactly) {
  const Packet in = posePacket();
  const PacketBytes bytes = encodePacket(in);
  Packet out;
  ASSERT_EQ(decodePacket(bytes.data(), bytes.size(), out), PacketError::kNone);
  EXPECT_EQ(out.sequence, 42u);
  EXPECT_TRUE(out.flag);
  EXPECT_EQ(out.timestamp_ns, in.timestamp_ns);
  EXPECT_EQ(out.pose.position.y, -0.2);
  EXPECT_EQ(out.pose.orientation.y, in.pose.orientation.y);
  EXPECT_EQ(out.buttons, 3u);

  Packet w;
  w.kind = PacketKind::kWrench;
  w.sequence = 7;
  w.wrench = {{1, 2, 3}, {-4, -5, -6}};
  w.echo_sequence = 41;
  const PacketBytes wb = encodePacket(w);
  ASSERT_EQ(decodePacket(wb.data(), wb.size(), out), PacketError::kNone);
  EXPECT_EQ(out.kind, PacketKind::kWrench);
  EXPECT_EQ(out.wrench.torque.y, -5);
  EXPECT_EQ(out.echo_sequence, 41u);
}

TEST(UdpPacket, LayoutIsLittleEndianAsDocumented) {
  const PacketBytes b = encodePacket(posePacket());
  EXPECT_EQ(b[0], 0x48);  // magic 0x54525348, low byte first
  EXPECT_EQ(b[3], 0x54);
  EXPECT_EQ(b[4], 1);   // version
  EXPECT_EQ(b[6], 1);   // kind pose
  EXPECT_EQ(b[8], 42);  // sequence
  EXPECT_EQ(b[80], 3);  // buttons
  double px;
  std::memcpy(&px, &b[24], 8);  // this host is little-endian, like the wire
  EXPECT_EQ(px, 0.1);
}

TEST(UdpPacket, TruncatedAndMalformedAreRejected) {
  PacketBytes b = encodePacket(posePacket());
  Packet out;
  EXPECT_EQ(decodePacket(b.data(), b.size() - 1, out), PacketError::kTruncated);
  EXPECT_EQ(decodePacket(b.data(), 0, out), PacketError::kTruncated);
  PacketBytes flipped = b;
  flipped[30] ^= 0x10;  // a bit flipped in the payload: the checksum catches it
  EXPECT_EQ(decodePacket(flipped.data(), flipped.size(), out), PacketError::kMalformed);
  PacketBytes magic = b;
  magic[0] = 0;
  EXPECT_EQ(decodePacket(magic.data(), magic.size(), out), PacketError::kMalformed);

  Packet nan = posePacket();
  nan.pose.position.x = std::numeric_limits<double>::quiet_NaN();
  const PacketBytes nb = encodePacket(nan);  // a correct checksum over a NaN
  EXPECT_EQ(decodePacket(nb.data(), nb.size(), out), PacketError::kMalformed);
  Packet skew = posePacket();
  skew.pose.orientation = {2, 0, 0, 0};  // not a unit quaternion
  const PacketBytes sb = encodePacket(skew);
  EXPECT_EQ(decodePacket(sb.data(), sb.size(), out), PacketError::kMalformed);
}

TEST(UdpPacket, SequenceOrderSurvivesWrapAround) {
  EXPECT_TRUE(sequenceAfter(1, 0));
  EXPECT_FALSE(sequenceAfter(0, 1));
  EXPECT_TRUE(sequenceAfter(2, 0xfffffffeu));
  EXPECT_FALSE(sequenceAfter(5, 5));
}

}  // namespace
}  // namespace torsion::device
