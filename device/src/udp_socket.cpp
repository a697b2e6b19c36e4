#include "torsion/device/udp_socket.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace torsion::device {

namespace {

sockaddr_in toSockaddr(const UdpEndpoint& e) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(e.port);
  a.sin_addr.s_addr = htonl(e.address);
  return a;
}

std::string describe(const UdpEndpoint& e) {
  in_addr a{};
  a.s_addr = htonl(e.address);
  char text[INET_ADDRSTRLEN] = {};
  inet_ntop(AF_INET, &a, text, sizeof text);
  return std::string(text) + ":" + std::to_string(e.port);
}

}  // namespace

Loaded<std::shared_ptr<UdpSocket>> UdpSocket::open(UdpEndpoint local) {
  using Out = Loaded<std::shared_ptr<UdpSocket>>;
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) return Out::fail(std::string("cannot create a UDP socket: ") + std::strerror(errno));
  sockaddr_in a = toSockaddr(local);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    return Out::fail("cannot bind UDP " + describe(local) + ": " + why);
  }
  socklen_t length = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &length);
  local.port = ntohs(a.sin_port);
  return Out{std::shared_ptr<UdpSocket>(new UdpSocket(fd, local)), {}};
}

UdpSocket::~UdpSocket() {
  ::close(fd_);
}

bool UdpSocket::send(const UdpEndpoint& to, const void* bytes, std::size_t size) {
  const sockaddr_in a = toSockaddr(to);
  return ::sendto(fd_, bytes, size, 0, reinterpret_cast<const sockaddr*>(&a), sizeof a) ==
         static_cast<ssize_t>(size);
}

long UdpSocket::receive(void* buffer, std::size_t capacity, UdpEndpoint& from) {
  sockaddr_in a{};
  socklen_t length = sizeof a;
  // MSG_TRUNC: the return value is the datagram's real length, so a long one is seen as such.
  const ssize_t n =
      ::recvfrom(fd_, buffer, capacity, MSG_TRUNC, reinterpret_cast<sockaddr*>(&a), &length);
  if (n < 0) return -1;
  from.address = ntohl(a.sin_addr.s_addr);
  from.port = ntohs(a.sin_port);
  return static_cast<long>(n);
}

bool parseIpv4(const std::string& text, std::uint32_t& address) {
  in_addr a{};
  if (::inet_pton(AF_INET, text.c_str(), &a) != 1) return false;
  address = ntohl(a.s_addr);
  return true;
}

}  // namespace torsion::device
