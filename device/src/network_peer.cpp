#include "torsion/device/network_peer.h"

#include <chrono>

namespace torsion::device {

Loaded<std::unique_ptr<NetworkPeer>> NetworkPeer::open(const UdpEndpoint& simulation,
                                                       Trajectory trajectory) {
  using Out = Loaded<std::unique_ptr<NetworkPeer>>;
  auto socket = UdpSocket::open(UdpEndpoint{simulation.address, 0});
  if (!socket) return Out::fail("network peer: " + socket.error);
  return Out{std::unique_ptr<NetworkPeer>(
                 new NetworkPeer(*socket.value, simulation, std::move(trajectory))),
             {}};
}

NetworkPeer::NetworkPeer(std::shared_ptr<UdpSocket> socket, UdpEndpoint simulation,
                         Trajectory trajectory)
    : socket_(std::move(socket)), simulation_(simulation), trajectory_(std::move(trajectory)) {}

void NetworkPeer::tick(double time) {
  sendPose(++sequence_, trajectory_.poseAt(time), trajectory_.buttonsAt(time), true);
  drain();
}

void NetworkPeer::sayGoodbye(double time) {
  sendPose(++sequence_, trajectory_.poseAt(time), trajectory_.buttonsAt(time), false, true);
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
  const PacketBytes bytes = encodePacket(packet);
  sendRaw(bytes.data(), bytes.size());
}

void NetworkPeer::sendRaw(const void* bytes, std::size_t size) {
  if (socket_->send(simulation_, bytes, size)) {
    ++stats_.sent;
  } else {
    ++stats_.send_failed;
  }
}

void NetworkPeer::drain() {
  unsigned char buffer[kPacketSize + 1];
  UdpEndpoint from;
  long size;
  while ((size = socket_->receive(buffer, sizeof buffer, from)) >= 0) {
    if (static_cast<std::size_t>(size) > kPacketSize) {
      ++stats_.truncated;
      continue;
    }
    Packet packet;
    if (filter_.accept(buffer, static_cast<std::size_t>(size), packet, stats_)) newest_ = packet;
  }
}

}  // namespace torsion::device
