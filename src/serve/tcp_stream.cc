#include "serve/tcp_stream.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>

#include "core/error.h"
#include "serve/udp_socket.h"

namespace twinsim {
namespace {

sockaddr_in Address(const std::string& address, int port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(ParseIpv4(address));
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  return a;
}

void NoDelay(int fd) {
  // A request and its answer are one small message each: never held back (Nagle).
  const int on = 1;
  (void)::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, sizeof on);
}

}  // namespace

bool WaitReadableFd(int fd, double timeout) {
  pollfd p{fd, POLLIN, 0};
  return ::poll(&p, 1, static_cast<int>(std::ceil(std::max(0.0, timeout) * 1000))) > 0;
}

TcpConnection::TcpConnection(int fd) : fd_(fd) {}

TcpConnection::~TcpConnection() {
  if (fd_ >= 0) ::close(fd_);
}

TcpConnection::TcpConnection(TcpConnection&& other) noexcept
    : fd_(other.fd_), buffer_(std::move(other.buffer_)), consumed_(other.consumed_), bad_(other.bad_) {
  other.fd_ = -1;
}

TcpConnection& TcpConnection::operator=(TcpConnection&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_;
    buffer_ = std::move(other.buffer_);
    consumed_ = other.consumed_;
    bad_ = other.bad_;
    other.fd_ = -1;
  }
  return *this;
}

bool TcpConnection::ReadAvailable() {
  // At most this much waits unread: a client that floods is read at the pace its
  // requests are answered, never into unbounded memory.
  constexpr std::size_t kMaxBuffered = 4 << 20;  // bytes
  // The messages taken since the last read go in one move, not one move each.
  buffer_.erase(0, consumed_);
  consumed_ = 0;
  char chunk[65536];
  while (buffer_.size() < kMaxBuffered) {
    const ssize_t n = ::recv(fd_, chunk, sizeof chunk, MSG_DONTWAIT);
    if (n > 0) {
      buffer_.append(chunk, static_cast<std::size_t>(n));
      continue;
    }
    if (n == 0) return false;  // closed by the peer
    if (errno == EINTR) continue;
    return errno == EAGAIN || errno == EWOULDBLOCK;
  }
  return true;
}

std::optional<std::string> TcpConnection::NextMessage(std::size_t max_bytes) {
  if (bad_) return std::nullopt;
  std::uint64_t length = 0;
  std::size_t i = consumed_;
  for (int shift = 0;; shift += 7) {
    if (i >= buffer_.size()) return std::nullopt;  // the length is still coming
    if (shift > 63) {
      bad_ = true;
      return std::nullopt;
    }
    const auto b = static_cast<unsigned char>(buffer_[i++]);
    length |= static_cast<std::uint64_t>(b & 0x7f) << shift;
    if (!(b & 0x80)) break;
  }
  if (length > max_bytes) {
    bad_ = true;
    return std::nullopt;
  }
  if (buffer_.size() - i < length) return std::nullopt;
  std::string message = buffer_.substr(i, static_cast<std::size_t>(length));
  consumed_ = i + static_cast<std::size_t>(length);
  return message;
}

bool TcpConnection::WriteMessage(const std::string& message, double timeout) {
  std::string bytes;
  for (std::uint64_t v = message.size(); ; v >>= 7) {
    if (v < 0x80) {
      bytes.push_back(static_cast<char>(v));
      break;
    }
    bytes.push_back(static_cast<char>((v & 0x7f) | 0x80));
  }
  bytes += message;
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::send(fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      pollfd p{fd_, POLLOUT, 0};
      if (::poll(&p, 1, static_cast<int>(1000 * timeout)) <= 0) return false;
      continue;
    }
    return false;
  }
  return true;
}

TcpListener::TcpListener(const std::string& address, int port) {
  if (port < 0 || port > 65535) throw InputError("port " + std::to_string(port) + " is not in 0..65535");
  const sockaddr_in a = Address(address, port);
  fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error(std::string("cannot open a TCP socket: ") + std::strerror(errno));
  const int on = 1;
  (void)::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0 || ::listen(fd_, 4) != 0) {
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    throw InputError("cannot listen on " + address + ":" + std::to_string(port) + " (TCP): " + std::strerror(err));
  }
}

TcpListener::~TcpListener() {
  if (fd_ >= 0) ::close(fd_);
}

int TcpListener::port() const {
  sockaddr_in a{};
  socklen_t len = sizeof a;
  if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len) != 0) return 0;
  return ntohs(a.sin_port);
}

std::optional<TcpConnection> TcpListener::Accept() {
  const int fd = ::accept4(fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
  if (fd < 0) return std::nullopt;
  NoDelay(fd);
  return TcpConnection(fd);
}

TcpConnection TcpConnect(const std::string& address, int port) {
  const sockaddr_in a = Address(address, port);
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error(std::string("cannot open a TCP socket: ") + std::strerror(errno));
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    const int err = errno;
    ::close(fd);
    throw InputError("cannot connect to " + address + ":" + std::to_string(port) + ": " + std::strerror(err));
  }
  NoDelay(fd);
  return TcpConnection(fd);
}

}  // namespace twinsim
