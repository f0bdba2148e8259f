#include "serve/udp_socket.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <stdexcept>

#include "core/error.h"

namespace twinsim {
namespace {

sockaddr_in ToSockaddr(const UdpEndpoint& e) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(e.address);
  a.sin_port = htons(static_cast<std::uint16_t>(e.port));
  return a;
}

int OpenNonBlocking() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error(std::string("cannot open a UDP socket: ") + std::strerror(errno));
  return fd;
}

}  // namespace

std::string UdpEndpoint::ToString() const {
  return std::to_string((address >> 24) & 255) + "." + std::to_string((address >> 16) & 255) + "." +
         std::to_string((address >> 8) & 255) + "." + std::to_string(address & 255) + ":" + std::to_string(port);
}

std::uint32_t ParseIpv4(const std::string& text) {
  in_addr a{};
  // inet_pton accepts exactly four decimal parts, nothing else.
  if (::inet_pton(AF_INET, text.c_str(), &a) != 1)
    throw InputError("'" + text + "' is not an IPv4 address (expected four numbers 0-255, e.g. 127.0.0.1)");
  return ntohl(a.s_addr);
}

bool IsMulticast(std::uint32_t address) { return (address >> 28) == 0xE; }

UdpSocket::UdpSocket() : fd_(OpenNonBlocking()) {}

UdpSocket::UdpSocket(const std::string& address, int port) {
  const std::uint32_t host = ParseIpv4(address);
  if (port < 0 || port > 65535) throw InputError("port " + std::to_string(port) + " is not in 0..65535");
  fd_ = OpenNonBlocking();
  const sockaddr_in a = ToSockaddr(UdpEndpoint{host, port});
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    throw InputError("cannot listen on " + UdpEndpoint{host, port}.ToString() + ": " + std::strerror(err));
  }
  // The arrival stamp measures how long a datagram waits for the loop; without it
  // (refused), Receive stamps the time it reads the datagram.
  const int on = 1;
  (void)::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
  // Datagrams lost to a full receive buffer are counted rather than unseen.
  (void)::setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on);
}

int UdpSocket::SetReceiveBuffer(int bytes) {
  // Linux doubles what it is given (for its bookkeeping) and reports the doubled size:
  // half is asked, so that the size reported is `bytes`. SO_RCVBUFFORCE passes
  // net.core.rmem_max where the process may (CAP_NET_ADMIN); elsewhere the kernel caps
  // SO_RCVBUF there.
  const int half = std::max(1, bytes / 2);
  if (::setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &half, sizeof half) != 0)
    (void)::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &half, sizeof half);
  return receive_buffer();
}

int UdpSocket::receive_buffer() const {
  int size = 0;
  socklen_t len = sizeof size;
  if (::getsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &size, &len) != 0) return 0;
  return size;
}

UdpSocket::~UdpSocket() {
  if (fd_ >= 0) ::close(fd_);
}

UdpSocket::UdpSocket(UdpSocket&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }

UdpSocket& UdpSocket::operator=(UdpSocket&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

int UdpSocket::port() const {
  sockaddr_in a{};
  socklen_t len = sizeof a;
  if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len) != 0) return 0;
  return ntohs(a.sin_port);
}

bool UdpSocket::SendTo(const std::string& bytes, const UdpEndpoint& to, std::string* error) const {
  const sockaddr_in a = ToSockaddr(to);
  const ssize_t n = ::sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&a), sizeof a);
  if (n == static_cast<ssize_t>(bytes.size())) return true;
  if (error != nullptr) {
    *error = n < 0 ? std::string(std::strerror(errno)) : "sent " + std::to_string(n) + " of " +
                                                              std::to_string(bytes.size()) + " bytes";
  }
  return false;
}

std::optional<Datagram> UdpSocket::Receive(std::size_t max_bytes) const {
  Datagram d;
  d.bytes.resize(max_bytes);
  sockaddr_in a{};
  iovec data{d.bytes.data(), d.bytes.size()};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t))];
  msghdr m{};
  m.msg_name = &a;
  m.msg_namelen = sizeof a;
  m.msg_iov = &data;
  m.msg_iovlen = 1;
  m.msg_control = control;
  m.msg_controllen = sizeof control;
  // MSG_TRUNC: the return value is the datagram's full size, even when cut to the buffer.
  const ssize_t n = ::recvmsg(fd_, &m, MSG_TRUNC);
  if (n < 0) return std::nullopt;  // nothing waiting (EAGAIN), or an error the next call sees again
  d.size = static_cast<std::size_t>(n);
  d.bytes.resize(std::min(d.size, max_bytes));
  d.from = UdpEndpoint{ntohl(a.sin_addr.s_addr), ntohs(a.sin_port)};
  for (cmsghdr* c = CMSG_FIRSTHDR(&m); c != nullptr; c = CMSG_NXTHDR(&m, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
      timespec t{};
      std::memcpy(&t, CMSG_DATA(c), sizeof t);
      d.arrival_ns = static_cast<long long>(t.tv_sec) * 1000000000LL + t.tv_nsec;
      d.kernel_stamp = true;
    } else if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
      std::uint32_t drops = 0;
      std::memcpy(&drops, CMSG_DATA(c), sizeof drops);
      d.kernel_drops = drops;
    }
  }
  d.read_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                  std::chrono::system_clock::now().time_since_epoch()).count();
  if (!d.kernel_stamp) d.arrival_ns = d.read_ns;
  return d;
}

void UdpSocket::SetMulticastSender(int ttl, bool loop, const std::string& interface_address) {
  auto refused = [](const std::string& what) {
    throw InputError("cannot send vision to a multicast group: the system refused " + what + ": " +
                     std::strerror(errno));
  };
  const unsigned char hops = static_cast<unsigned char>(ttl), looped = loop ? 1 : 0;
  if (ttl < 1 || ttl > 255) throw InputError("multicast ttl " + std::to_string(ttl) + " is not in 1..255");
  if (::setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_TTL, &hops, sizeof hops) != 0) refused("the ttl");
  if (::setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_LOOP, &looped, sizeof looped) != 0) refused("the loop");
  if (!interface_address.empty()) {
    in_addr a{};
    a.s_addr = htonl(ParseIpv4(interface_address));
    if (::setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_IF, &a, sizeof a) != 0)
      refused("the interface " + interface_address + " (not an address of this host?)");
  }
}

int WaitReadable(const std::vector<const UdpSocket*>& sockets, double timeout) {
  std::vector<pollfd> fds;
  for (const UdpSocket* s : sockets) fds.push_back(pollfd{s->fd(), POLLIN, 0});
  const auto ns = static_cast<long long>(std::ceil(std::max(0.0, timeout) * 1e9));
  const timespec wait{static_cast<time_t>(ns / 1000000000LL), static_cast<long>(ns % 1000000000LL)};
  if (::ppoll(fds.data(), fds.size(), &wait, nullptr) <= 0) return -1;
  for (std::size_t i = 0; i < fds.size(); ++i)
    if (fds[i].revents & (POLLIN | POLLERR)) return static_cast<int>(i);
  return -1;
}

}  // namespace twinsim
