// The serve socket on the loopback: each datagram's arrival stamp, and the datagrams
// the kernel drops when the receive buffer is full, counted.
#include "serve/udp_socket.h"

#include <gtest/gtest.h>

#include <chrono>
#include <string>

namespace twinsim {
namespace {

UdpEndpoint LoopbackPort(int port) { return UdpEndpoint{ParseIpv4("127.0.0.1"), port}; }

TEST(UdpSocket, EveryDatagramIsReceivedOrCountedAsDroppedByTheKernel) {
  UdpSocket receiver("127.0.0.1", 0), sender("127.0.0.1", 0);
  const int granted = receiver.SetReceiveBuffer(4096);
  EXPECT_LT(granted, 65536);
  const int burst = 5000;
  const std::string bytes(200, 'x');
  for (int i = 0; i < burst; ++i) ASSERT_TRUE(sender.SendTo(bytes, LoopbackPort(receiver.port())));
  int received = 0;
  while (receiver.Receive(1024)) ++received;
  EXPECT_GT(received, 0);
  EXPECT_LT(received, burst);
  // The count rides on the next datagram the buffer takes.
  ASSERT_TRUE(sender.SendTo(bytes, LoopbackPort(receiver.port())));
  std::optional<Datagram> last;
  for (int tries = 0; tries < 100 && !last; ++tries) {
    WaitReadable({&receiver}, 0.05);
    last = receiver.Receive(1024);
  }
  ASSERT_TRUE(last);
  ASSERT_TRUE(last->kernel_drops);
  EXPECT_EQ(received + static_cast<long long>(*last->kernel_drops), burst);
  EXPECT_TRUE(last->kernel_stamp);
}

TEST(UdpSocket, ABiggerBufferHoldsTheBurst) {
  UdpSocket receiver("127.0.0.1", 0), sender("127.0.0.1", 0);
  // 1000 datagrams of 200 bytes cost about 1.3 MB of the kernel's accounting on loopback.
  const int granted = receiver.SetReceiveBuffer(4 << 20);
  if (granted < (4 << 20)) GTEST_SKIP() << "the kernel grants " << granted << " bytes (net.core.rmem_max, no CAP_NET_ADMIN)";
  const std::string bytes(200, 'x');
  for (int i = 0; i < 1000; ++i) ASSERT_TRUE(sender.SendTo(bytes, LoopbackPort(receiver.port())));
  int received = 0;
  std::optional<Datagram> d;
  while ((d = receiver.Receive(1024))) {
    ++received;
    EXPECT_FALSE(d->kernel_drops);
  }
  EXPECT_EQ(received, 1000);
}

TEST(UdpSocket, ARefusedSendSaysWhy) {
  UdpSocket sender;
  std::string why;
  EXPECT_FALSE(sender.SendTo("x", UdpEndpoint{ParseIpv4("255.255.255.255"), 9}, &why));
  EXPECT_FALSE(why.empty());
  EXPECT_FALSE(sender.SendTo(std::string(70000, 'x'), LoopbackPort(9), &why));
  EXPECT_NE(why.find("too long"), std::string::npos) << why;
}

}  // namespace
}  // namespace twinsim
