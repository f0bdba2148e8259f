// TCP over IPv4 for twinsim serve's synchronous interface: a listening socket that
// accepts one client at a time, and a connection that reads and writes messages framed
// as the league's game controller frames them (protobuf's length-delimited form: the
// length as a varint, then the bytes). Plain POSIX sockets, non-blocking reads.
//
//   TcpListener listener("127.0.0.1", 10303);
//   std::optional<TcpConnection> client = listener.Accept();        // none waiting: nothing
//   while (auto m = client->NextMessage(1 << 20)) Handle(*m);
//   client->WriteMessage(reply);
#pragma once

#include <cstddef>
#include <optional>
#include <string>

namespace twinsim {

class TcpConnection {
 public:
  explicit TcpConnection(int fd);
  ~TcpConnection();
  TcpConnection(TcpConnection&& other) noexcept;
  TcpConnection& operator=(TcpConnection&& other) noexcept;
  TcpConnection(const TcpConnection&) = delete;
  TcpConnection& operator=(const TcpConnection&) = delete;

  int fd() const { return fd_; }
  // Reads what has arrived, up to 4 MB waiting unread (never blocks); false once the
  // peer has closed the connection or it failed.
  bool ReadAvailable();
  // The next whole message read, if any. A message announced longer than `max_bytes`,
  // or a length that is no varint, makes the stream unusable: bad() turns true.
  std::optional<std::string> NextMessage(std::size_t max_bytes);
  bool bad() const { return bad_; }
  // Writes `message` with its length in front, waiting (at most `timeout` s) while the
  // peer's window is full; false when the connection failed or timed out (the stream may
  // then hold part of the message: drop the connection).
  bool WriteMessage(const std::string& message, double timeout = 5);

 private:
  int fd_ = -1;
  std::string buffer_;        // bytes read
  std::size_t consumed_ = 0;  // of them, taken as messages (dropped at the next read)
  bool bad_ = false;
};

class TcpListener {
 public:
  // Listens on `address`:`port` (port 0: a free port the system picks). Throws
  // InputError naming the address when it cannot.
  TcpListener(const std::string& address, int port);
  ~TcpListener();
  TcpListener(const TcpListener&) = delete;
  TcpListener& operator=(const TcpListener&) = delete;

  int port() const;
  int fd() const { return fd_; }
  // A client waiting to be accepted, or nothing. Never blocks.
  std::optional<TcpConnection> Accept();

 private:
  int fd_ = -1;
};

// Connects to `address`:`port` (blocking; for clients and tests). Throws InputError.
TcpConnection TcpConnect(const std::string& address, int port);

// Waits at most `timeout` s for `fd` to be readable; true when it is.
bool WaitReadableFd(int fd, double timeout);

}  // namespace twinsim
