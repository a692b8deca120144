// The connection registry without a server: the per-address cap and the peer-closed probe that
// lets a one-shot render stop when its client hangs up.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include "http/connection_guard.h"

namespace brdfa::server {
namespace {

TEST(ConnectionRegistry, CountsConnectionsPerAddressUpToTheCap) {
  ConnectionRegistry registry(2);
  EXPECT_TRUE(registry.add("10.0.0.1", 1000, 100));
  EXPECT_TRUE(registry.add("10.0.0.1", 1001, 101));
  EXPECT_FALSE(registry.add("10.0.0.1", 1002, 102)) << "a third from the same address";
  EXPECT_TRUE(registry.add("10.0.0.2", 1000, 103)) << "another address has its own count";
  EXPECT_EQ(registry.openFrom("10.0.0.1"), 2);

  registry.remove("10.0.0.1", 1000);
  EXPECT_EQ(registry.openFrom("10.0.0.1"), 1);
  EXPECT_TRUE(registry.add("10.0.0.1", 1002, 102)) << "a closed connection makes room";
  registry.remove("10.0.0.1", 4242);  // never added: changes nothing
  EXPECT_EQ(registry.openFrom("10.0.0.1"), 2);
}

TEST(ConnectionRegistry, SeesThePeerCloseButNotItsPipelinedData) {
  int pair[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM, 0, pair), 0);
  ConnectionRegistry registry(4);
  ASSERT_TRUE(registry.add("127.0.0.1", 5000, pair[0]));

  EXPECT_FALSE(registry.peerClosed("127.0.0.1", 5000)) << "an idle open connection";
  ASSERT_EQ(::write(pair[1], "GET / HTTP/1.1\r\n", 16), 16);
  EXPECT_FALSE(registry.peerClosed("127.0.0.1", 5000)) << "unread input is not a close";
  ::close(pair[1]);
  EXPECT_TRUE(registry.peerClosed("127.0.0.1", 5000)) << "closed, even behind unread input";
  EXPECT_FALSE(registry.peerClosed("127.0.0.1", 5001)) << "an unknown connection";

  registry.remove("127.0.0.1", 5000);
  EXPECT_FALSE(registry.peerClosed("127.0.0.1", 5000)) << "no longer registered";
  ::close(pair[0]);
}

}  // namespace
}  // namespace brdfa::server
