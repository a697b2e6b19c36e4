#include "torsion/device/network_peer.h"

#include <algorithm>
#include <chrono>
#include <cstdint>

namespace torsion::device {

Loaded<std::unique_ptr<NetworkPeer>> NetworkPeer::open(const UdpEndpoint& simulation,
                                                       Trajectory trajectory,
                                                       std::optional<PacketKey> key,
                                                       const DeviceLimits& limits,
                                                       const WatchdogSettings& watchdog) {
  using Out = Loaded<std::unique_ptr<NetworkPeer>>;
  auto socket = UdpSocket::open(UdpEndpoint{simulation.address, 0});
  if (!socket) return Out::fail("network peer: " + socket.error);
  return Out{
      std::unique_ptr<NetworkPeer>(new NetworkPeer(*socket.value, simulation, std::move(trajectory),
                                                   std::move(key), limits, watchdog)),
      {}};
}

NetworkPeer::NetworkPeer(std::shared_ptr<UdpSocket> socket, UdpEndpoint simulation,
                         Trajectory trajectory, std::optional<PacketKey> key,
                         const DeviceLimits& limits, const WatchdogSettings& watchdog)
    : socket_(std::move(socket)),
      simulation_(simulation),
      trajectory_(std::move(trajectory)),
      key_(std::move(key)),
      session_(key_ ? randomNonce() : 0),
      watchdog_(watchdog, limits) {}

DeviceLimits NetworkPeer::peerLimits() {
  DeviceLimits l;
  l.max_force = 30;
  l.max_torque = 3;
  return l;
}

std::uint32_t NetworkPeer::nextSequence() {
  // Signed sequences never wrap (packet_stats.h): a new session starts instead.
  if (key() && sequence_ == UINT32_MAX) newSession();
  return ++sequence_;
}

void NetworkPeer::newSession() {
  ended_session_ = session_;
  session_ = randomNonce();
  device_nonce_ = 0;
  retired_.clear();
  sequence_ = 0;
  filter_ = PacketFilter(PacketKind::kWrench, key());
}

void NetworkPeer::tick(double time) {
  sendPose(nextSequence(), trajectory_.poseAt(time), trajectory_.buttonsAt(time), true);
  drain(time);
  rendered_ = watchdog_.render(time);
}

void NetworkPeer::sayGoodbye(double time) {
  sendPose(nextSequence(), trajectory_.poseAt(time), trajectory_.buttonsAt(time), false, true);
  if (key()) newSession();
}

void NetworkPeer::sendPose(std::uint32_t sequence, const Pose& pose, std::uint32_t buttons,
                           bool alive, bool goodbye) {
  Packet packet;
  packet.kind = PacketKind::kPose;
  packet.sequence = sequence;
  packet.flag = alive;
  packet.goodbye = goodbye;
  packet.timestamp_ns =
      static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                     std::chrono::steady_clock::now().time_since_epoch())
                                     .count());
  packet.pose = pose;
  packet.buttons = buttons;
  if (key()) {
    packet.session = session_;
    packet.device_nonce = device_nonce_;
    const SignedPacketBytes bytes = encodeSignedPacket(packet, *key());
    sendRaw(bytes.data(), bytes.size());
  } else {
    const PacketBytes bytes = encodePacket(packet);
    sendRaw(bytes.data(), bytes.size());
  }
}

void NetworkPeer::sendRaw(const void* bytes, std::size_t size) {
  if (socket_->send(simulation_, bytes, size)) {
    ++stats_.sent;
  } else {
    ++stats_.send_failed;
  }
}

bool NetworkPeer::inSession(const Packet& packet) {
  if (packet.session == session_ && packet.device_nonce == device_nonce_) return true;
  // The device's answer to the goodbye of the session just ended (its zero wrench): nothing to
  // render, nothing wrong.
  if (packet.session == ended_session_ && ended_session_ != 0) return false;
  const bool retired =
      std::find(retired_.begin(), retired_.end(), packet.device_nonce) != retired_.end();
  if (packet.session != session_ || packet.device_nonce == 0 || retired) {
    ++stats_.replayed;  // signed, but for another session of this key
    return false;
  }
  // The device's challenge for this session (the first, or a newer one: the device lost the
  // session, or restarted): its nonce replaces the earlier one for good, and the new device
  // session numbers its wrenches afresh.
  if (device_nonce_ != 0) retired_.push_back(device_nonce_);
  device_nonce_ = packet.device_nonce;
  filter_ = PacketFilter(PacketKind::kWrench, key());
  return true;
}

void NetworkPeer::drain(double time) {
  unsigned char buffer[kMaxPacketSize + 1];
  UdpEndpoint from;
  long size;
  while ((size = socket_->receive(buffer, sizeof buffer, from)) >= 0) {
    if (static_cast<std::size_t>(size) > kMaxPacketSize) {
      ++stats_.truncated;
      continue;
    }
    Packet packet;
    if (!filter_.decode(buffer, static_cast<std::size_t>(size), packet, stats_)) continue;
    if (key() && !inSession(packet)) continue;
    if (filter_.inOrder(packet, stats_)) {
      newest_ = packet;
      watchdog_.receive(packet.wrench, time);
    }
  }
}

}  // namespace torsion::device
