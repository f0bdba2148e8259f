// UDP over IPv4 for twinsim serve: a bound, non-blocking socket that sends and receives
// whole datagrams, each stamped with the time the kernel received it, and a wait on
// several sockets at once. Plain POSIX sockets (Linux's SO_TIMESTAMPNS for the stamps).
//
//   UdpSocket control("127.0.0.1", 10300);       // port 0: any free port
//   if (WaitReadable({&control}, 0.05) >= 0)
//     while (auto d = control.Receive(8192)) Handle(d->bytes, d->from);
//   control.SendTo(reply, d->from);
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace twinsim {

// An IPv4 address and port, both in host byte order.
struct UdpEndpoint {
  std::uint32_t address = 0;
  int port = 0;
  // "127.0.0.1:10300".
  std::string ToString() const;
  bool operator==(const UdpEndpoint& o) const { return address == o.address && port == o.port; }
  bool operator!=(const UdpEndpoint& o) const { return !(*this == o); }
};

// Parses a dotted IPv4 address ("127.0.0.1"). Throws InputError naming `text` otherwise.
std::uint32_t ParseIpv4(const std::string& text);
// Whether `address` (host order) is a multicast group (224.0.0.0/4).
bool IsMulticast(std::uint32_t address);

// One datagram received.
struct Datagram {
  std::string bytes;      // at most the size asked for
  UdpEndpoint from;
  std::size_t size = 0;   // bytes the sender sent: larger than bytes.size() when cut off
  // ns since the Unix epoch (CLOCK_REALTIME, as std::chrono::system_clock): when the
  // kernel received the datagram, or, when it gave no stamp, when Receive read it.
  long long arrival_ns = 0;
  bool kernel_stamp = false;  // arrival_ns is the kernel's receive time
  long long read_ns = 0;      // ns since the Unix epoch: when Receive read it
  // Datagrams the kernel dropped on this socket (its receive buffer full) since the
  // socket was opened, as of this one's arrival (SO_RXQ_OVFL); the kernel says so only
  // once it has dropped one: none means none dropped yet.
  std::optional<std::uint32_t> kernel_drops;
  bool truncated() const { return size > bytes.size(); }
};

class UdpSocket {
 public:
  // Binds to `address`:`port` (port 0: a free port the system picks) and asks the kernel
  // to stamp each datagram's arrival and to count the datagrams it drops. Throws
  // InputError naming the address when the socket cannot be bound (in use, not this
  // host's address).
  UdpSocket(const std::string& address, int port);
  // An unbound socket for sending only (the system binds it on the first send).
  UdpSocket();
  ~UdpSocket();
  UdpSocket(UdpSocket&& other) noexcept;
  UdpSocket& operator=(UdpSocket&& other) noexcept;
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;

  // The port the socket is bound to (0 before an unbound socket's first send).
  int port() const;
  int fd() const { return fd_; }

  // Sends one datagram; false when the system refused it (a full buffer, a broadcast
  // address, a datagram over 64 kB), with the reason in *error when given.
  bool SendTo(const std::string& bytes, const UdpEndpoint& to, std::string* error = nullptr) const;
  // Asks for a receive buffer of `bytes` of the kernel's accounting (which counts each
  // datagram's overhead too, as getsockopt SO_RCVBUF reports it): beyond twice
  // net.core.rmem_max only with CAP_NET_ADMIN. Returns the size the kernel granted.
  int SetReceiveBuffer(int bytes);
  int receive_buffer() const;
  // The next datagram waiting, at most `max_bytes` of it kept (its full size is
  // reported), or nothing when none is waiting. Never blocks.
  std::optional<Datagram> Receive(std::size_t max_bytes) const;
  // For sending to a multicast group: hops a datagram may take (`ttl`, 1: this network
  // only), whether this host's own members receive it (`loop`), and the interface it
  // leaves by (an address of that interface; empty: the kernel's route to the group).
  // Throws InputError naming what the system refused.
  void SetMulticastSender(int ttl, bool loop, const std::string& interface_address);

 private:
  int fd_ = -1;
};

// Waits at most `timeout` s (to the nanosecond: the real-time pace depends on it) for a
// datagram on any of `sockets`; returns the index of the first that has one, -1 on
// timeout (or a signal).
int WaitReadable(const std::vector<const UdpSocket*>& sockets, double timeout);

}  // namespace twinsim
