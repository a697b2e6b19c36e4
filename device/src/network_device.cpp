#include "torsion/device/network_device.h"

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
  while ((size = socket_->receive(buffer, sizeof buffer, from)) >= 0) {
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
    if (!freshSession(packet) || !filter_.inOrder(packet, stats_)) continue;
    newest_ = packet;
    peer_ = from;
    session_ = packet.session;
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

bool NetworkDevice::freshSession(const Packet& packet) {
  if (!key()) return true;
  for (const std::uint64_t ended : ended_sessions_) {
    if (packet.session == ended) {
      ++stats_.replayed;
      return false;
    }
  }
  // The bound peer's address with a new session id: the peer restarted; its old session ends.
  if (have_peer_ && packet.session != session_) endSession();
  return true;
}

void NetworkDevice::endSession() {
  write(Wrench{});  // the departing peer's device must not keep the last force
  if (key()) ended_sessions_.push_back(session_);  // grows only with authenticated sessions
  have_peer_ = false;
  newest_ = Packet{};
  session_ = 0;
  filter_ = PacketFilter(PacketKind::kPose, key());  // the next peer's sequence starts afresh
  last_accepted_time_ = -1e300;
}

void NetworkDevice::write(const Wrench& wrench) {
  if (!have_peer_) return;
  Packet packet;
  packet.kind = PacketKind::kWrench;
  packet.sequence = ++sent_sequence_;
  packet.timestamp_ns = monotonicNanoseconds();
  packet.wrench = wrench;
  packet.flag = true;  // the loop only writes wrenches that passed its safety filter
  packet.echo_sequence = newest_.sequence;
  packet.session = session_;
  bool sent;
  if (key()) {
    const SignedPacketBytes bytes = encodeSignedPacket(packet, *key());
    sent = socket_->send(peer_, bytes.data(), bytes.size());
  } else {
    const PacketBytes bytes = encodePacket(packet);
    sent = socket_->send(peer_, bytes.data(), bytes.size());
  }
  if (sent) {
    ++stats_.sent;
  } else {
    ++stats_.send_failed;
  }
}

}  // namespace torsion::device
