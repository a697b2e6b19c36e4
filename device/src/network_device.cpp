#include "torsion/device/network_device.h"

#include <algorithm>
#include <chrono>

namespace torsion::device {

namespace {

std::uint64_t monotonicNanoseconds() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::steady_clock::now().time_since_epoch())
                                        .count());
}

}  // namespace

Loaded<std::unique_ptr<NetworkDevice>> NetworkDevice::open(const NetworkDeviceSettings& settings) {
  using Out = Loaded<std::unique_ptr<NetworkDevice>>;
  if (!(settings.timeout > 0)) return Out::fail("network device: timeout must be positive");
  auto socket = UdpSocket::open(settings.local);
  if (!socket) return Out::fail("network device: " + socket.error);
  return Out{std::unique_ptr<NetworkDevice>(new NetworkDevice(settings, *socket.value)), {}};
}

NetworkDevice::NetworkDevice(const NetworkDeviceSettings& settings,
                             std::shared_ptr<UdpSocket> socket)
    : settings_(settings), socket_(std::move(socket)) {}

NetworkDevice::~NetworkDevice() {
  write(Wrench{});
}

std::string NetworkDevice::name() const {
  return "network(udp port " + std::to_string(socket_->local().port) + ")";
}

DeviceSample NetworkDevice::read(double time) {
  unsigned char buffer[kMaxPacketSize + 1];  // one spare byte: longer datagrams are seen as such
  UdpEndpoint from;
  long size;
  // Bounded: a flood must not hold the tick; what is left waits in the socket for the next reads.
  last_read_datagrams_ = 0;
  while (last_read_datagrams_ < kMaxDatagramsPerRead &&
         (size = socket_->receive(buffer, sizeof buffer, from)) >= 0) {
    ++last_read_datagrams_;
    Packet packet;
    const std::size_t kept = std::min(static_cast<std::size_t>(size), sizeof buffer);
    if (static_cast<std::size_t>(size) != kept || kept > kMaxPacketSize) {
      ++stats_.truncated;  // longer than any packet
      continue;
    }
    // Validate (and, with a key, authenticate) first: a bad datagram must not end a session.
    if (!filter_.decode(buffer, kept, packet, stats_)) continue;
    if (have_peer_ && !(from == peer_)) {
      if (time - last_accepted_time_ <= settings_.session_timeout) {
        ++stats_.foreign;  // the session belongs to its first peer
        continue;
      }
      endSession();  // the bound peer went silent: the session is over
    }
    if ((key() && !inSession(packet, from)) || !filter_.inOrder(packet, stats_)) continue;
    newest_ = packet;
    peer_ = from;
    have_peer_ = true;
    last_accepted_time_ = time;
    if (packet.goodbye) {
      endSession();
      break;  // the goodbye is the session's last word: later datagrams wait for the next read
    }
  }
  DeviceSample sample;
  sample.time = time;
  sample.pose = newest_.pose;
  sample.buttons = newest_.buttons;
  sample.alive = have_peer_ && newest_.flag && time - last_accepted_time_ <= settings_.timeout;
  return sample;
}

bool NetworkDevice::inSession(const Packet& packet, const UdpEndpoint& from) {
  if (have_peer_ && packet.session == session_ && packet.device_nonce == nonce_) return true;
  if (packet.device_nonce != 0 && challenged_ && from == challenge_to_ &&
      packet.session == challenge_session_ && packet.device_nonce == challenge_nonce_) {
    // The answer to the pending challenge: its session binds. A session still bound here is the
    // same address's (another address's poses were refused as foreign above): its peer started
    // a new session, and the old one ends.
    if (have_peer_) endSession();
    session_ = packet.session;
    nonce_ = packet.device_nonce;
    challenged_ = false;
    return true;
  }
  // A late hello of the bound session was answered already.
  if (packet.device_nonce == 0 && have_peer_ && packet.session == session_) return false;
  // A pose carrying a device nonce that is not the current one: recorded in an earlier session
  // (a replay), or its peer lost the session (it timed out, or this device restarted). Refused
  // either way; the challenge lets a live peer of the key open a new session.
  if (packet.device_nonce != 0) ++stats_.replayed;
  challenge(packet.session, from);
  return false;
}

void NetworkDevice::challenge(std::uint64_t session, const UdpEndpoint& to) {
  if (!(challenged_ && to == challenge_to_ && session == challenge_session_)) {
    challenged_ = true;
    challenge_to_ = to;
    challenge_session_ = session;
    challenge_nonce_ = randomNonce();
  }
  Packet packet;
  packet.kind = PacketKind::kWrench;
  packet.flag = false;  // force off: a challenge is not a wrench to render
  packet.session = challenge_session_;
  packet.device_nonce = challenge_nonce_;
  send(packet, to);
}

void NetworkDevice::endSession() {
  write(Wrench{});  // the departing peer's device must not keep the last force
  have_peer_ = false;
  newest_ = Packet{};
  session_ = 0;
  nonce_ = 0;  // retired: no packet of this session verifies as current again
  filter_ = PacketFilter(PacketKind::kPose, key());  // the next peer's sequence starts afresh
  last_accepted_time_ = -1e300;
}

void NetworkDevice::write(const Wrench& wrench) {
  if (!have_peer_) return;
  Packet packet;
  packet.kind = PacketKind::kWrench;
  packet.wrench = wrench;
  packet.flag = true;  // the loop only writes wrenches that passed its safety filter
  packet.echo_sequence = newest_.sequence;
  packet.session = session_;
  packet.device_nonce = nonce_;
  send(packet, peer_);
}

void NetworkDevice::send(Packet packet, const UdpEndpoint& to) {
  packet.sequence = ++sent_sequence_;
  packet.timestamp_ns = monotonicNanoseconds();
  bool sent;
  if (key()) {
    const SignedPacketBytes bytes = encodeSignedPacket(packet, *key());
    sent = socket_->send(to, bytes.data(), bytes.size());
  } else {
    const PacketBytes bytes = encodePacket(packet);
    sent = socket_->send(to, bytes.data(), bytes.size());
  }
  if (sent) {
    ++stats_.sent;
  } else {
    ++stats_.send_failed;
  }
}

}  // namespace torsion::device
