// Authenticated packets (packet_key.h, docs/haptic-devices.md "Authentication"): hostile UDP peers
// on loopback against a device and a peer that share a key. Loopback datagrams are queued before
// sendto returns, so nothing here waits; clocks are fake.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>
#include <vector>

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

std::unique_ptr<NetworkDevice> openSignedDevice(std::uint16_t port = 0) {
  NetworkDeviceSettings settings;
  settings.local.port = port;  // 0: any free port, tests may run in parallel
  settings.limits = defaultDeviceLimits();
  settings.key = keyOf(kSecret);
  auto device = NetworkDevice::open(settings);
  EXPECT_TRUE(device) << device.error;
  return device ? std::move(*device.value) : nullptr;
}

Signed openSigned() {
  std::unique_ptr<NetworkDevice> device = openSignedDevice();
  auto peer = NetworkPeer::open(device->local(), kHere, keyOf(kSecret));
  EXPECT_TRUE(peer) << peer.error;
  return {std::move(device), std::move(*peer.value)};
}

// The handshake, tick by tick: the peer's hello (sequence 1) draws the device's challenge; the
// peer's next tick sends a second hello (2) and takes the challenge; its third sends the first
// pose the device takes (3), which binds the session.
void connect(NetworkPeer& peer, NetworkDevice& device, double time) {
  for (int k = 0; k < 2; ++k) {
    peer.tick(time);
    EXPECT_FALSE(device.read(time).alive);  // a hello never drives the hand
  }
  peer.tick(time);
  EXPECT_TRUE(device.read(time).alive);
}

std::unique_ptr<NetworkPeer> intruder(const NetworkDevice& device,
                                      std::optional<PacketKey> key = {}) {
  auto peer = NetworkPeer::open(device.local(), kThere, std::move(key));
  EXPECT_TRUE(peer) << peer.error;
  return std::move(*peer.value);
}

Packet pose(std::uint32_t sequence, std::uint64_t session, std::uint64_t device_nonce, double x) {
  Packet p;
  p.kind = PacketKind::kPose;
  p.sequence = sequence;
  p.session = session;
  p.device_nonce = device_nonce;
  p.flag = true;
  p.pose = Pose{{x, 0, 0}, {}};
  return p;
}

TEST(PacketAuthentication, ASignedPacketDecodesOnlyUnderItsKey) {
  const PacketKey key = keyOf(kSecret);
  const SignedPacketBytes bytes = encodeSignedPacket(pose(7, 42, 43, 0.25), key);
  Packet out;
  ASSERT_EQ(decodePacket(bytes.data(), bytes.size(), out, &key), PacketError::kNone);
  EXPECT_EQ(out.sequence, 7u);
  EXPECT_EQ(out.session, 42u);
  EXPECT_EQ(out.device_nonce, 43u);
  EXPECT_DOUBLE_EQ(out.pose.position.x, 0.25);

  const PacketKey other = keyOf(kOtherSecret);
  EXPECT_EQ(decodePacket(bytes.data(), bytes.size(), out, &other), PacketError::kUnauthenticated);
  EXPECT_EQ(decodePacket(bytes.data(), bytes.size(), out), PacketError::kUnauthenticated);
  // Version, sequence, pose, peer nonce, device nonce, MAC.
  for (std::size_t at : {4u, 8u, 30u, 88u, 96u, 104u, 135u}) {
    SignedPacketBytes flipped = bytes;
    flipped[at] ^= 0x01;
    EXPECT_NE(decodePacket(flipped.data(), flipped.size(), out, &key), PacketError::kNone) << at;
  }
  // An unsigned packet, however well-formed, is refused once a key is configured.
  const PacketBytes plain = encodePacket(pose(8, 0, 0, 0.25));
  EXPECT_EQ(decodePacket(plain.data(), plain.size(), out, &key), PacketError::kUnauthenticated);
  EXPECT_EQ(decodePacket(plain.data(), plain.size(), out), PacketError::kNone);
}

TEST(PacketAuthentication, SignedPeerAndDeviceExchangePosesAndWrenches) {
  Signed s = openSigned();
  connect(*s.peer, *s.device, 0.0);
  EXPECT_NE(s.peer->deviceNonce(), 0u);  // the device's challenge came
  s.peer->tick(0.001);
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
  connect(*s.peer, *s.device, 0.0);  // binds the session with the pose of sequence 3
  const PacketKey key = keyOf(kSecret);

  auto wrong_key = intruder(*s.device, keyOf(kOtherSecret));
  auto no_key = intruder(*s.device);
  for (int k = 1; k <= 3; ++k) {
    wrong_key->tick(0.001 * k);
    no_key->tick(0.001 * k);
  }
  // A packet of the legitimate session, recorded and replayed from the same address (a spoofed
  // source): its sequence is not new.
  const SignedPacketBytes recorded =
      encodeSignedPacket(pose(3, s.peer->session(), s.peer->deviceNonce(), 9), key);
  s.peer->sendRaw(recorded.data(), recorded.size());
  // The same recording, and a validly signed pose with a much higher sequence, from another port.
  auto other_port = intruder(*s.device);
  other_port->sendRaw(recorded.data(), recorded.size());
  const SignedPacketBytes ahead =
      encodeSignedPacket(pose(1000, s.peer->session(), s.peer->deviceNonce(), 9), key);
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
  connect(*s.peer, *s.device, 0.0);
  const SignedPacketBytes recorded =
      encodeSignedPacket(pose(4, s.peer->session(), s.peer->deviceNonce(), 9), key);
  s.peer->sayGoodbye(0.001);
  EXPECT_FALSE(s.device->read(0.001).alive);
  // The recorded pose of the ended session, sent later from another port: refused.
  auto attacker = intruder(*s.device);
  attacker->sendRaw(recorded.data(), recorded.size());
  EXPECT_FALSE(s.device->read(0.002).alive);
  EXPECT_EQ(s.device->stats().replayed, 1u);
  // A new session of a key holder binds as usual.
  auto next = intruder(*s.device, keyOf(kSecret));
  connect(*next, *s.device, 0.003);
  EXPECT_DOUBLE_EQ(s.device->read(0.003).pose.position.x, 5.0);
}

TEST(PacketAuthentication, APeerRefusesWrenchesOfAnotherSession) {
  Signed s = openSigned();
  connect(*s.peer, *s.device, 0.0);
  const PacketKey key = keyOf(kSecret);
  Packet w;
  w.kind = PacketKind::kWrench;
  w.sequence = 99;
  w.session = s.peer->session() + 1;  // signed with the key, but for another session
  w.device_nonce = s.peer->deviceNonce();
  w.wrench = {{7, 0, 0}, {0, 0, 0}};
  const SignedPacketBytes bytes = encodeSignedPacket(w, key);
  auto sender = UdpSocket::open(UdpEndpoint{0x7f000001, 0});
  ASSERT_TRUE(sender) << sender.error;
  ASSERT_TRUE((*sender.value)->send(s.peer->local(), bytes.data(), bytes.size()));
  s.peer->tick(0.001);
  EXPECT_EQ(s.peer->stats().replayed, 1u);
  EXPECT_DOUBLE_EQ(s.peer->newestWrench().force.x, 0.0);
}

// A man in the middle that records: the peer sends to it, it forwards to the device and the
// device's answers back to the peer, keeping a copy of every datagram the peer sent.
struct Recorder {
  explicit Recorder(UdpEndpoint device_at) : device(device_at) {
    auto opened = UdpSocket::open(UdpEndpoint{0x7f000001, 0});
    EXPECT_TRUE(opened) << opened.error;
    socket = *opened.value;
  }
  void pump() {
    unsigned char bytes[512];
    UdpEndpoint from;
    long size;
    while ((size = socket->receive(bytes, sizeof bytes, from)) >= 0) {
      const auto n = static_cast<std::size_t>(size);
      if (from == device) {
        socket->send(peer, bytes, n);
      } else {
        peer = from;
        recorded.emplace_back(bytes, bytes + n);
        socket->send(device, bytes, n);
      }
    }
  }
  std::shared_ptr<UdpSocket> socket;
  UdpEndpoint device;
  UdpEndpoint peer;
  std::vector<std::vector<unsigned char>> recorded;
};

// The reference peer drives `device` through `recorder` for `ticks` ticks from `time`.
void drive(NetworkPeer& peer, Recorder& recorder, NetworkDevice& device, double time, int ticks) {
  for (int k = 0; k < ticks; ++k) {
    peer.tick(time + 0.001 * k);
    recorder.pump();
    (void)device.read(time + 0.001 * k);
    recorder.pump();
  }
}

// Recorded poses that carry a device nonce (the hellos before the challenge carry none).
std::uint64_t posesWithADeviceNonce(const std::vector<std::vector<unsigned char>>& recorded) {
  const PacketKey key = keyOf(kSecret);
  std::uint64_t n = 0;
  for (const auto& bytes : recorded) {
    Packet p;
    EXPECT_EQ(decodePacket(bytes.data(), bytes.size(), p, &key), PacketError::kNone);
    n += p.device_nonce != 0 ? 1 : 0;
  }
  return n;
}

TEST(PacketAuthentication, RecordedSessionsNeverTakeTheHandAfterTheGoodbye) {
  // An earlier run: an attacker on the path records a whole session of a real peer.
  std::vector<std::vector<unsigned char>> earlier_run;
  {
    std::unique_ptr<NetworkDevice> earlier = openSignedDevice();
    Recorder recorder(earlier->local());
    auto peer = NetworkPeer::open(recorder.socket->local(), kThere, keyOf(kSecret));
    ASSERT_TRUE(peer) << peer.error;
    drive(**peer.value, recorder, *earlier, 0.0, 10);
    const DeviceSample sample = earlier->read(0.01);
    ASSERT_TRUE(sample.alive);
    ASSERT_DOUBLE_EQ(sample.pose.position.x, 5.0);
    earlier_run = recorder.recorded;  // that run is killed: no goodbye
  }
  // This run: the real peer's session, recorded too, ends with its goodbye.
  std::unique_ptr<NetworkDevice> device = openSignedDevice();
  Recorder recorder(device->local());
  auto opened = NetworkPeer::open(recorder.socket->local(), kHere, keyOf(kSecret));
  ASSERT_TRUE(opened) << opened.error;
  NetworkPeer& peer = **opened.value;
  drive(peer, recorder, *device, 0.0, 10);
  ASSERT_TRUE(device->read(0.01).alive);
  ASSERT_DOUBLE_EQ(device->read(0.01).pose.position.x, 0.01);
  peer.sayGoodbye(0.011);
  recorder.pump();
  ASSERT_FALSE(device->read(0.011).alive);
  const std::vector<std::vector<unsigned char>> this_run = recorder.recorded;
  const std::uint64_t accepted = device->stats().accepted;
  ASSERT_EQ(device->stats().replayed, 0u);

  // Both recordings replayed, each from the address its session had and from another one.
  auto attacker = UdpSocket::open(UdpEndpoint{0x7f000001, 0});
  ASSERT_TRUE(attacker) << attacker.error;
  const std::vector<const std::vector<std::vector<unsigned char>>*> recordings = {&earlier_run,
                                                                                  &this_run};
  for (const auto* recorded : recordings) {
    for (const auto& bytes : *recorded) {
      recorder.socket->send(device->local(), bytes.data(), bytes.size());
      (*attacker.value)->send(device->local(), bytes.data(), bytes.size());
    }
    const DeviceSample sample = device->read(0.012);
    EXPECT_FALSE(sample.alive);
    EXPECT_NE(sample.pose.position.x, 5.0);
    EXPECT_NE(sample.pose.position.x, 0.01);
  }
  const std::uint64_t replays =
      2 * (posesWithADeviceNonce(earlier_run) + posesWithADeviceNonce(this_run));
  EXPECT_GE(replays, 2u * (8 + 9));  // 10 ticks each, 2 of them hellos; this run's goodbye
  EXPECT_EQ(device->stats().replayed, replays);
  EXPECT_EQ(device->stats().accepted, accepted);  // not one replayed packet was taken
  EXPECT_FALSE(device->read(0.013).alive);

  // The real peer's new session binds as usual (its replayed hellos drew challenges it ignores).
  recorder.pump();
  drive(peer, recorder, *device, 0.02, 3);
  const DeviceSample sample = device->read(0.022);
  EXPECT_TRUE(sample.alive);
  EXPECT_DOUBLE_EQ(sample.pose.position.x, 0.01);
  device->write({{2, 0, 0}, {0, 0, 0}});
  recorder.pump();
  peer.tick(0.023);
  EXPECT_DOUBLE_EQ(peer.newestWrench().force.x, 2.0);
  EXPECT_EQ(device->stats().replayed, replays);
}

TEST(PacketAuthentication, APeerWhoseDeviceRestartedIsChallengedAndBindsAgain) {
  Signed s = openSigned();
  connect(*s.peer, *s.device, 0.0);
  const std::uint64_t first = s.peer->deviceNonce();
  const std::uint16_t port = s.device->local().port;
  s.device.reset();  // the simulation restarts on the same port; the peer keeps going
  s.device = openSignedDevice(port);
  ASSERT_TRUE(s.device);
  s.peer->tick(0.001);  // carries the old device nonce: refused, and answered with a challenge
  EXPECT_FALSE(s.device->read(0.001).alive);
  EXPECT_EQ(s.device->stats().replayed, 1u);
  s.peer->tick(0.002);  // refused too; the peer takes the new challenge
  EXPECT_FALSE(s.device->read(0.002).alive);
  EXPECT_NE(s.peer->deviceNonce(), first);
  s.peer->tick(0.003);
  EXPECT_TRUE(s.device->read(0.003).alive);
  s.device->write({{3, 0, 0}, {0, 0, 0}});
  s.peer->tick(0.004);  // the new device's wrench sequence starts afresh: taken
  EXPECT_DOUBLE_EQ(s.peer->newestWrench().force.x, 3.0);
}

TEST(PacketAuthentication, APeerOfTheEarlierSignedVersionIsRefusedAsSuch) {
  std::unique_ptr<NetworkDevice> device = openSignedDevice();
  // Version 2: 88 bytes of header and payload, a peer nonce, a MAC; no device nonce.
  Packet p = pose(1, 42, 0, 0.25);
  SignedPacketBytes v3 = encodeSignedPacket(p, keyOf(kSecret));
  unsigned char v2[kOldSignedPacketSize] = {};
  std::memcpy(v2, v3.data(), 96);
  v2[4] = 2;
  auto old_peer = UdpSocket::open(UdpEndpoint{0x7f000001, 0});
  ASSERT_TRUE(old_peer) << old_peer.error;
  (*old_peer.value)->send(device->local(), v2, sizeof v2);
  EXPECT_FALSE(device->read(0.0).alive);
  EXPECT_EQ(device->stats().old_version, 1u);
  EXPECT_EQ(device->stats().rejected(), 1u);
  Packet out;
  EXPECT_EQ(decodePacket(v2, sizeof v2, out, nullptr), PacketError::kOldVersion);
}

long threadCpuNanoseconds() {
  timespec t{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<long>(t.tv_sec) * 1000000000L + t.tv_nsec;
}

long wallNanoseconds() {
  timespec t{};
  ::clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<long>(t.tv_sec) * 1000000000L + t.tv_nsec;
}

// A flood of valid signed poses of the bound session (a runaway driver, or a replayer that
// holds the key): each read() takes at most kMaxDatagramsPerRead datagrams (deterministic), and
// costs the loop's thread a bounded CPU time. 64 receives and HMACs take about 0.25 ms, and a
// read that took the whole flood would take some 400 ms (100000 at about 4 us); the bound, 40 ms,
// lies between with room on both sides: a loaded 2-core VM once charged a capped read 7.2 ms of
// thread CPU (the hypervisor's stolen time counts as the thread's). It is thread CPU time: the
// two senders preempt the reader (wall-clock reads of 5-15 ms, with or without the cap), which
// is scheduling, not the read's cost. Without the cap a read took all the socket held (its whole
// buffer: 256 datagrams, about 1 ms, with the default 208 KiB) or, while the flood outpaced it,
// more: however long the flood lasted.
TEST(PacketAuthentication, AFloodOfValidPacketsCostsEachReadABoundedTime) {
  Signed s = openSigned();
  connect(*s.peer, *s.device, 0.0);
  // Signed beforehand, so that the sender outpaces the receiver (which checks every MAC).
  constexpr std::uint32_t kFlood = 100000;
  const PacketKey key = keyOf(kSecret);
  std::vector<SignedPacketBytes> flood(kFlood);
  for (std::uint32_t k = 0; k < kFlood; ++k)
    flood[k] =
        encodeSignedPacket(pose(100 + k, s.peer->session(), s.peer->deviceNonce(), 0.02), key);
  // Two senders from the bound peer's address: together they outpace the receiver.
  std::atomic<int> flooding{2};
  NetworkPeer& peer = *s.peer;
  const auto send = [&peer, &flood, &flooding](std::size_t first) {
    for (std::size_t k = first; k < flood.size(); k += 2)
      peer.sendRaw(flood[k].data(), flood[k].size());
    --flooding;
  };
  std::thread flooder(send, 0);
  std::thread flooder2(send, 1);
  int max_datagrams = 0;
  long max_cpu = 0;
  long max_wall = 0;
  long reads = 0;
  double time = 0.001;
  while (true) {
    const bool last = flooding.load() == 0;  // the flood is all queued: this read drains the rest
    const long cpu0 = threadCpuNanoseconds();
    const long wall0 = wallNanoseconds();
    (void)s.device->read(time);
    max_cpu = std::max(max_cpu, threadCpuNanoseconds() - cpu0);
    max_wall = std::max(max_wall, wallNanoseconds() - wall0);
    max_datagrams = std::max(max_datagrams, s.device->lastReadDatagrams());
    ++reads;
    time += 0.001;
    if (last && s.device->lastReadDatagrams() < kMaxDatagramsPerRead) break;
  }
  flooder.join();
  flooder2.join();
  std::printf(
      "flood of %u valid packets: %ld reads, %llu accepted; worst read %.3f ms CPU "
      "(%.3f ms wall), at most %d datagrams\n",
      kFlood, reads, static_cast<unsigned long long>(s.device->stats().accepted.load()),
      1e-6 * static_cast<double>(max_cpu), 1e-6 * static_cast<double>(max_wall), max_datagrams);
  EXPECT_LE(max_datagrams, kMaxDatagramsPerRead);
  EXPECT_LT(max_cpu, 40000000L);
  EXPECT_GT(s.device->stats().accepted, 1u);
  EXPECT_EQ(s.device->stats().replayed, 0u);
  EXPECT_DOUBLE_EQ(s.device->read(time).pose.position.x, 0.02);
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
