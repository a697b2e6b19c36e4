#include "torsion/device/network_device.h"

#include <gtest/gtest.h>

#include "torsion/device/haptic_loop.h"
#include "torsion/device/network_peer.h"
#include "torsion/device/scripted_device.h"

// Loopback UDP: a datagram sent to a local socket is queued before sendto returns, so these
// tests need no waiting. Clocks are fake.
namespace torsion::device {
namespace {

struct Loopback {
  std::unique_ptr<NetworkDevice> device;
  std::unique_ptr<NetworkPeer> peer;
};

Loopback open(Trajectory trajectory = Trajectory({{0, Pose{{0.01, 0.02, 0.03}, {}}}}, {})) {
  NetworkDeviceSettings settings;
  settings.local.port = 0;  // any free port: tests may run in parallel
  settings.limits = defaultDeviceLimits();
  auto device = NetworkDevice::open(settings);
  if (!device) {
    ADD_FAILURE() << device.error;
    return {};
  }
  auto peer = NetworkPeer::open((*device.value)->local(), std::move(trajectory));
  if (!peer) {
    ADD_FAILURE() << peer.error;
    return {};
  }
  return {std::move(*device.value), std::move(*peer.value)};
}

TEST(NetworkDevice, PoseInWrenchOutRoundTrip) {
  Loopback l = open();
  ASSERT_TRUE(l.device && l.peer);          // open() reported why
  EXPECT_FALSE(l.device->read(0.0).alive);  // nothing heard yet
  l.peer->tick(0.0);
  const DeviceSample s = l.device->read(0.001);
  EXPECT_TRUE(s.alive);
  EXPECT_DOUBLE_EQ(s.pose.position.z, 0.03);
  l.device->write({{1, -2, 3}, {0.1, 0.2, -0.3}});
  l.peer->tick(0.002);
  EXPECT_DOUBLE_EQ(l.peer->newestWrench().force.y, -2);
  EXPECT_DOUBLE_EQ(l.peer->newestWrench().torque.z, -0.3);
  EXPECT_EQ(l.peer->newestEcho(), 1u);  // the wrench answers the peer's first pose
  EXPECT_EQ(l.device->stats().accepted, 1u);
  EXPECT_EQ(l.device->stats().rejected(), 0u);
}

TEST(NetworkDevice, ASessionBelongsToItsFirstPeerUntilGoodbye) {
  Loopback l = open();
  ASSERT_TRUE(l.device && l.peer);  // open() reported why
  auto intruder = NetworkPeer::open(l.device->local(), Trajectory({{0, Pose{{5, 5, 5}, {}}}}, {}));
  ASSERT_TRUE(intruder) << intruder.error;
  l.peer->tick(0.0);  // the first peer binds the session
  (*intruder.value)->tick(0.0);
  DeviceSample s = l.device->read(0.001);
  EXPECT_DOUBLE_EQ(s.pose.position.z, 0.03);  // the intruder's pose was not taken
  EXPECT_EQ(l.device->stats().foreign, 1u);
  l.device->write({{1, 0, 0}, {0, 0, 0}});
  (*intruder.value)->tick(0.002);
  EXPECT_EQ((*intruder.value)->stats().accepted, 0u);  // no wrench went to the intruder

  // Goodbye: the first peer gets a zero wrench and the device is free for the next peer.
  l.peer->sayGoodbye(0.003);
  s = l.device->read(0.004);
  EXPECT_FALSE(s.alive);
  (*intruder.value)->tick(0.005);
  s = l.device->read(0.006);
  EXPECT_TRUE(s.alive);
  EXPECT_DOUBLE_EQ(s.pose.position.x, 5.0);
  l.peer->tick(0.007);  // now the first peer is the stranger; its tick also drains its inbox
  EXPECT_EQ(l.peer->newestWrench().force.x, 0.0);
  (void)l.device->read(0.008);
  // Foreign: the intruder's poses at 0 and 0.002 (before the goodbye), the first peer's at 0.007.
  EXPECT_EQ(l.device->stats().foreign, 3u);
}

TEST(NetworkDevice, ASilentPeerLosesItsSessionAfterTheSessionTimeout) {
  Loopback l = open();
  ASSERT_TRUE(l.device && l.peer);  // open() reported why
  auto next = NetworkPeer::open(l.device->local(), Trajectory({{0, Pose{{5, 5, 5}, {}}}}, {}));
  ASSERT_TRUE(next) << next.error;
  l.peer->tick(0.0);
  (void)l.device->read(0.0);
  (*next.value)->tick(0.5);
  EXPECT_DOUBLE_EQ(l.device->read(0.5).pose.position.x, 0.01);  // within the 1 s session
  (*next.value)->tick(1.2);
  const DeviceSample s = l.device->read(1.2);  // the first peer silent for 1.2 s
  EXPECT_TRUE(s.alive);
  EXPECT_DOUBLE_EQ(s.pose.position.x, 5.0);
  EXPECT_EQ(l.device->stats().foreign, 1u);
}

TEST(NetworkDevice, ClosingSendsTheBoundPeerAZeroWrench) {
  Loopback l = open();
  ASSERT_TRUE(l.device && l.peer);  // open() reported why
  l.peer->tick(0.0);
  (void)l.device->read(0.001);
  l.device->write({{3, 0, 0}, {0, 0, 0.5}});
  l.peer->tick(0.002);
  ASSERT_EQ(l.peer->newestWrench().force.x, 3.0);
  l.device.reset();  // whatever ends the run (signal, error) destroys the device
  l.peer->tick(0.003);
  EXPECT_EQ(l.peer->newestWrench().force.x, 0.0);
  EXPECT_EQ(l.peer->newestWrench().torque.z, 0.0);
}

TEST(NetworkDevice, BadPacketsAreDroppedAndCounted) {
  Loopback l = open();
  ASSERT_TRUE(l.device && l.peer);  // open() reported why
  const Pose good{{0.05, 0, 0}, {}};
  l.peer->sendPose(10, good, 1, true);
  const unsigned char junk[10] = {1, 2, 3};
  l.peer->sendRaw(junk, sizeof junk);  // truncated
  unsigned char longer[200] = {};
  l.peer->sendRaw(longer, sizeof longer);  // too long: counted as truncated too
  Packet p;
  p.sequence = 11;
  p.pose = good;
  PacketBytes corrupt = encodePacket(p);
  corrupt[40] ^= 0xff;
  l.peer->sendRaw(corrupt.data(), corrupt.size());        // malformed
  l.peer->sendPose(10, Pose{{9, 9, 9}, {}}, 0, true);     // duplicate
  l.peer->sendPose(9, Pose{{7, 7, 7}, {}}, 0, true);      // out of order
  l.peer->sendPose(13, Pose{{0.06, 0, 0}, {}}, 1, true);  // good; 11 and 12 lost
  Packet wrong_way;
  wrong_way.kind = PacketKind::kWrench;
  wrong_way.sequence = 14;
  const PacketBytes ww = encodePacket(wrong_way);
  l.peer->sendRaw(ww.data(), ww.size());  // a wrench sent to the device: malformed here

  const DeviceSample s = l.device->read(0.0);
  const PacketStats& st = l.device->stats();
  EXPECT_EQ(st.accepted, 2u);
  EXPECT_EQ(st.truncated, 2u);
  EXPECT_EQ(st.malformed, 2u);
  EXPECT_EQ(st.duplicate, 1u);
  EXPECT_EQ(st.out_of_order, 1u);
  EXPECT_EQ(st.lost, 2u);
  EXPECT_TRUE(s.alive);
  EXPECT_DOUBLE_EQ(s.pose.position.x, 0.06);  // only good packets moved the pose
}

TEST(NetworkDevice, SilentPeerMeansDeadDevice) {
  Loopback l = open();
  ASSERT_TRUE(l.device && l.peer);  // open() reported why
  l.peer->tick(0.0);
  EXPECT_TRUE(l.device->read(0.0).alive);
  EXPECT_TRUE(l.device->read(0.04).alive);   // within the 50 ms timeout
  EXPECT_FALSE(l.device->read(0.06).alive);  // beyond it
  l.peer->sendPose(100, Pose{}, 0, false);   // a peer that says its arm is off
  EXPECT_FALSE(l.device->read(0.061).alive);
}

TEST(NetworkDevice, LoopRoundTripWithTheReferencePeer) {
  // The peer plays a trajectory; the loop reads it, the "simulation" answers with a spring
  // wrench; the peer receives the loop's safe output.
  Loopback l = open(Trajectory({{0, Pose{}}, {1, Pose{{0.1, 0, 0}, {}}}}, {{0, 1u}}));
  ASSERT_TRUE(l.device && l.peer);  // open() reported why
  HapticLoopSettings settings;
  HapticLoop loop(*l.device, settings);
  HandCommand command;
  for (int k = 0; k <= 1000; ++k) {
    const double t = 0.001 * k;
    l.peer->tick(t);
    loop.tick(t);
    loop.commands().read(command);
    SimulationWrench w;
    w.step = static_cast<std::uint64_t>(k + 1);
    w.command_tick = command.tick;
    w.grabbed = command.grab_requests > 0;
    w.pose = command.pose;
    w.wrench.force = {-100 * command.pose.position.x, 0, 0};  // 100 N/m spring
    loop.wrenches().write(w);
  }
  l.peer->tick(1.001);
  EXPECT_EQ(command.grab_requests, 1u);  // button 1 came through the network
  EXPECT_NEAR(command.pose.position.x, 0.1, 1e-12);
  // The force reached the peer, opposing the motion; the loop lags the pose by one tick.
  EXPECT_NEAR(l.peer->newestWrench().force.x, -10.0, 0.15);
  EXPECT_EQ(l.device->stats().rejected(), 0u);
  EXPECT_EQ(l.peer->stats().rejected(), 0u);
}

}  // namespace
}  // namespace torsion::device
