#pragma once
// A non-blocking IPv4 UDP socket (POSIX), owned RAII. Loopback by default: the network device
// talks to a driver process on the same machine.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "torsion/device/loaded.h"

namespace torsion::device {

struct UdpEndpoint {
  std::uint32_t address = 0x7f000001;  ///< IPv4, host order; 127.0.0.1
  std::uint16_t port = 0;
  bool operator==(const UdpEndpoint& o) const { return address == o.address && port == o.port; }
};

class UdpSocket {
 public:
  /// Binds `local` (port 0: any free port). Errors say which address and why.
  static Loaded<std::shared_ptr<UdpSocket>> open(UdpEndpoint local);
  ~UdpSocket();
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;

  /// The bound endpoint (with the port the system chose).
  UdpEndpoint local() const { return local_; }
  /// Sends one datagram; false when the system refused it (the caller counts it).
  bool send(const UdpEndpoint& to, const void* bytes, std::size_t size);
  /// Receives one datagram without waiting: its size, or -1 when none is queued. Datagrams
  /// longer than `capacity` are cut and reported with their full length.
  long receive(void* buffer, std::size_t capacity, UdpEndpoint& from);

 private:
  UdpSocket(int fd, UdpEndpoint local) : fd_(fd), local_(local) {}
  int fd_;
  UdpEndpoint local_;
};

/// "127.0.0.1" -> address in host order; false when it is not a dotted IPv4 address.
bool parseIpv4(const std::string& text, std::uint32_t& address);

}  // namespace torsion::device
