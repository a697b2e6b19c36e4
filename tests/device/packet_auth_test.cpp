// Authenticated packets (packet_key.h, docs/haptics.md "Authentication"): hostile UDP peers on
// loopback against a device and a peer that share a key. Loopback datagrams are queued before
// sendto returns, so nothing here waits; clocks are fake.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "torsion/device/haptic_loop.h"
#include "torsion/device/network_device.h"
#include "torsion/device/network_peer.h"
#include "torsion/device/packet_key.h"
#include "torsion/device/scripted_device.h"

namespace torsion::device {
namespace {

PacketKey keyOf(const std::string& secret) {
  Loaded<PacketKey> key = PacketKey::fromSecret(secret, "test");
  EXPECT_TRUE(key) << key.error;
  return *key.value;
}

const std::string kSecret = "0123456789abcdef0123456789abcdef0123456789abcdef";
const std::string kOtherSecret = "fedcba9876543210fedcba9876543210fedcba9876543210";
const Trajectory kHere({{0, Pose{{0.01, 0.02, 0.03}, {}}}}, {});
const Trajectory kThere({{0, Pose{{5, 5, 5}, {}}}}, {});

struct Signed {
  std::unique_ptr<NetworkDevice> device;
  std::unique_ptr<NetworkPeer> peer;
};

Signed openSigned() {
  NetworkDeviceSettings settings;
  settings.local.port = 0;
  settings.limits = defaultDeviceLimits();
  settings.key = keyOf(kSecret);
  auto device = NetworkDevice::open(settings);
  EXPECT_TRUE(device) << device.error;
  auto peer = NetworkPeer::open((*device.value)->local(), kHere, keyOf(kSecret));
  EXPECT_TRUE(peer) << peer.error;
  return {std::move(*device.value), std::move(*peer.value)};
}

std::unique_ptr<NetworkPeer> intruder(const NetworkDevice& device,
                                      std::optional<PacketKey> key = {}) {
  auto peer = NetworkPeer::open(device.local(), kThere, std::move(key));
  EXPECT_TRUE(peer) << peer.error;
  return std::move(*peer.value);
}

Packet pose(std::uint32_t sequence, std::uint64_t session, double x) {
  Packet p;
  p.kind = PacketKind::kPose;
  p.sequence = sequence;
  p.session = session;
  p.flag = true;
  p.pose = Pose{{x, 0, 0}, {}};
  return p;
}

TEST(PacketAuthentication, ASignedPacketDecodesOnlyUnderItsKey) {
  const PacketKey key = keyOf(kSecret);
  const SignedPacketBytes bytes = encodeSignedPacket(pose(7, 42, 0.25), key);
  Packet out;
  ASSERT_EQ(decodePacket(bytes.data(), bytes.size(), out, &key), PacketError::kNone);
  EXPECT_EQ(out.sequence, 7u);
  EXPECT_EQ(out.session, 42u);
  EXPECT_DOUBLE_EQ(out.pose.position.x, 0.25);

  const PacketKey other = keyOf(kOtherSecret);
  EXPECT_EQ(decodePacket(bytes.data(), bytes.size(), out, &other), PacketError::kUnauthenticated);
  EXPECT_EQ(decodePacket(bytes.data(), bytes.size(), out), PacketError::kUnauthenticated);
  for (std::size_t at : {4u, 8u, 30u, 88u, 100u, 127u}) {  // version, sequence, pose, session, MAC
    SignedPacketBytes flipped = bytes;
    flipped[at] ^= 0x01;
    EXPECT_NE(decodePacket(flipped.data(), flipped.size(), out, &key), PacketError::kNone) << at;
  }
  // An unsigned packet, however well-formed, is refused once a key is configured.
  const PacketBytes plain = encodePacket(pose(8, 0, 0.25));
  EXPECT_EQ(decodePacket(plain.data(), plain.size(), out, &key), PacketError::kUnauthenticated);
  EXPECT_EQ(decodePacket(plain.data(), plain.size(), out), PacketError::kNone);
}

TEST(PacketAuthentication, SignedPeerAndDeviceExchangePosesAndWrenches) {
  Signed s = openSigned();
  s.peer->tick(0.0);
  const DeviceSample sample = s.device->read(0.001);
  EXPECT_TRUE(sample.alive);
  EXPECT_DOUBLE_EQ(sample.pose.position.z, 0.03);
  s.device->write({{1, -2, 3}, {0, 0, 0.5}});
  s.peer->tick(0.002);
  EXPECT_DOUBLE_EQ(s.peer->newestWrench().force.y, -2);
  EXPECT_EQ(s.device->stats().rejected(), 0u);
  EXPECT_EQ(s.peer->stats().rejected(), 0u);
  EXPECT_TRUE(s.device->authenticated());
}

TEST(PacketAuthentication, HostilePeersAreRejectedAndCountedWhileTheLegitimatePeerKeepsControl) {
  Signed s = openSigned();
  s.peer->tick(0.0);  // binds the session
  ASSERT_TRUE(s.device->read(0.0).alive);
  const PacketKey key = keyOf(kSecret);

  auto wrong_key = intruder(*s.device, keyOf(kOtherSecret));
  auto no_key = intruder(*s.device);
  for (int k = 1; k <= 3; ++k) {
    wrong_key->tick(0.001 * k);
    no_key->tick(0.001 * k);
  }
  // A packet of the legitimate session, recorded and replayed from the same address (a spoofed
  // source): its sequence is not new.
  const SignedPacketBytes recorded = encodeSignedPacket(pose(1, s.peer->session(), 9), key);
  s.peer->sendRaw(recorded.data(), recorded.size());
  // The same recording, and a validly signed pose with a much higher sequence, from another port.
  auto other_port = intruder(*s.device);
  other_port->sendRaw(recorded.data(), recorded.size());
  const SignedPacketBytes ahead = encodeSignedPacket(pose(1000, s.peer->session(), 9), key);
  other_port->sendRaw(ahead.data(), ahead.size());

  DeviceSample sample = s.device->read(0.004);
  const PacketStats& st = s.device->stats();
  EXPECT_EQ(st.unauthenticated, 6u);  // 3 with the wrong key, 3 unsigned
  EXPECT_EQ(st.duplicate, 1u);        // the replay from the bound address
  EXPECT_EQ(st.foreign, 2u);          // the two from another port
  EXPECT_EQ(st.accepted, 1u);
  EXPECT_DOUBLE_EQ(sample.pose.position.x, 0.01);  // nobody else moved the hand

  // The legitimate peer keeps control, and only it receives wrenches.
  s.peer->tick(0.005);
  sample = s.device->read(0.005);
  EXPECT_TRUE(sample.alive);
  EXPECT_EQ(s.device->stats().accepted, 2u);
  s.device->write({{2, 0, 0}, {0, 0, 0}});
  s.peer->tick(0.006);
  wrong_key->tick(0.006);
  no_key->tick(0.006);
  EXPECT_DOUBLE_EQ(s.peer->newestWrench().force.x, 2.0);
  EXPECT_EQ(wrong_key->stats().accepted, 0u);
  EXPECT_EQ(no_key->stats().accepted, 0u);
}

TEST(PacketAuthentication, AnEndedSessionCannotBeReplayedToBindAgain) {
  Signed s = openSigned();
  const PacketKey key = keyOf(kSecret);
  s.peer->tick(0.0);
  ASSERT_TRUE(s.device->read(0.0).alive);
  const SignedPacketBytes recorded = encodeSignedPacket(pose(2, s.peer->session(), 9), key);
  s.peer->sayGoodbye(0.001);
  EXPECT_FALSE(s.device->read(0.001).alive);
  // The recorded pose of the ended session, sent later from another port: refused.
  auto attacker = intruder(*s.device);
  attacker->sendRaw(recorded.data(), recorded.size());
  EXPECT_FALSE(s.device->read(0.002).alive);
  EXPECT_EQ(s.device->stats().replayed, 1u);
  // A new session of a key holder binds as usual.
  auto next = intruder(*s.device, keyOf(kSecret));
  next->tick(0.003);
  const DeviceSample sample = s.device->read(0.003);
  EXPECT_TRUE(sample.alive);
  EXPECT_DOUBLE_EQ(sample.pose.position.x, 5.0);
}

TEST(PacketAuthentication, APeerRefusesWrenchesOfAnotherSession) {
  Signed s = openSigned();
  s.peer->tick(0.0);
  (void)s.device->read(0.0);
  const PacketKey key = keyOf(kSecret);
  Packet w;
  w.kind = PacketKind::kWrench;
  w.sequence = 99;
  w.session = s.peer->session() + 1;  // signed with the key, but for another session
  w.wrench = {{7, 0, 0}, {0, 0, 0}};
  const SignedPacketBytes bytes = encodeSignedPacket(w, key);
  auto sender = UdpSocket::open(UdpEndpoint{0x7f000001, 0});
  ASSERT_TRUE(sender) << sender.error;
  ASSERT_TRUE((*sender.value)->send(s.peer->local(), bytes.data(), bytes.size()));
  s.peer->tick(0.001);
  EXPECT_EQ(s.peer->stats().replayed, 1u);
  EXPECT_DOUBLE_EQ(s.peer->newestWrench().force.x, 0.0);
}

TEST(PacketAuthentication, AnUnkeyedDeviceRefusesSignedPackets) {
  NetworkDeviceSettings settings;
  settings.local.port = 0;
  auto device = NetworkDevice::open(settings);
  ASSERT_TRUE(device) << device.error;
  auto peer = intruder(**device.value, keyOf(kSecret));
  peer->tick(0.0);
  EXPECT_FALSE((*device.value)->read(0.0).alive);
  EXPECT_EQ((*device.value)->stats().unauthenticated, 1u);
}

// Key files: each failure is an error naming the file and what to do.
class KeyFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("torsion_key_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  std::string write(const std::string& name, const std::string& text, mode_t mode) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << text;
    ::chmod(path.c_str(), mode);
    return path;
  }
  std::filesystem::path dir_;
};

TEST_F(KeyFile, AGoodKeyFileLoadsAndATrailingNewlineIsNotPartOfTheKey) {
  const std::string path = write("good.key", kSecret + "\n", 0600);
  Loaded<PacketKey> key = PacketKey::fromFile(path);
  ASSERT_TRUE(key) << key.error;
  const PacketKey same = keyOf(kSecret);
  const unsigned char data[3] = {1, 2, 3};
  const Mac mac = same.mac(data, sizeof data);
  EXPECT_TRUE(key.value->verify(mac.data(), data, sizeof data));
}

TEST_F(KeyFile, MissingShortSharedOrNonRegularKeyFilesAreClearErrors) {
  const std::string missing = (dir_ / "missing.key").string();
  Loaded<PacketKey> key = PacketKey::fromFile(missing);
  ASSERT_FALSE(key);
  EXPECT_EQ(key.error, "key file " + missing + ": cannot open: No such file or directory");

  const std::string short_key = write("short.key", "tooshort\n", 0600);
  key = PacketKey::fromFile(short_key);
  ASSERT_FALSE(key);
  EXPECT_EQ(key.error, "key file " + short_key +
                           ": the key has 8 bytes, fewer than the 32 required (make one with: "
                           "openssl rand -hex 32)");

  const std::string shared = write("shared.key", kSecret, 0644);
  key = PacketKey::fromFile(shared);
  ASSERT_FALSE(key);
  EXPECT_EQ(key.error,
            "key file " + shared + ": other users can access it; restrict it with chmod 600");

  const std::string fifo = (dir_ / "fifo.key").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  key = PacketKey::fromFile(fifo);  // must not block
  ASSERT_FALSE(key);
  EXPECT_NE(key.error.find("key file " + fifo + ": "), std::string::npos) << key.error;
  EXPECT_NE(key.error.find("not a regular file"), std::string::npos) << key.error;

  const std::string directory = (dir_ / "a_directory.key").string();
  std::filesystem::create_directory(directory);
  ::chmod(directory.c_str(), 0700);
  key = PacketKey::fromFile(directory);
  ASSERT_FALSE(key);
  EXPECT_NE(key.error.find("key file " + directory + ": "), std::string::npos) << key.error;
  EXPECT_NE(key.error.find("not a regular file"), std::string::npos) << key.error;

  if (::geteuid() != 0) {  // root reads any file whatever its mode
    const std::string unreadable = write("unreadable.key", kSecret, 0000);
    key = PacketKey::fromFile(unreadable);
    ASSERT_FALSE(key);
    EXPECT_EQ(key.error, "key file " + unreadable + ": cannot open: Permission denied");
  }
}

TEST_F(KeyFile, TheEnvironmentGivesAKeyFileOrAKeyOrNothing) {
  ::unsetenv(kKeyFileVariable);
  ::unsetenv(kKeyVariable);
  Loaded<std::optional<PacketKey>> key = PacketKey::fromEnvironment();
  ASSERT_TRUE(key) << key.error;
  EXPECT_FALSE(key.value->has_value());

  ::setenv(kKeyVariable, "short", 1);
  key = PacketKey::fromEnvironment();
  ASSERT_FALSE(key);
  EXPECT_NE(key.error.find("TORSION_HAPTIC_KEY: the key has 5 bytes"), std::string::npos)
      << key.error;

  ::setenv(kKeyVariable, kSecret.c_str(), 1);
  key = PacketKey::fromEnvironment();
  ASSERT_TRUE(key) << key.error;
  EXPECT_TRUE(key.value->has_value());

  // The file variable wins, and its errors say where the path came from.
  const std::string missing = (dir_ / "nope.key").string();
  ::setenv(kKeyFileVariable, missing.c_str(), 1);
  key = PacketKey::fromEnvironment();
  ASSERT_FALSE(key);
  EXPECT_EQ(key.error,
            "key file " + missing +
                ": cannot open: No such file or directory (from TORSION_HAPTIC_KEY_FILE)");
  ::unsetenv(kKeyFileVariable);
  ::unsetenv(kKeyVariable);
}

}  // namespace
}  // namespace torsion::device
