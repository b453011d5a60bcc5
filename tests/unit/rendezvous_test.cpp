// Scene affinity: the rendezvous weights (which the Python client must reproduce bit for bit), the
// balance and stability that make rendezvous hashing worth having, and endpoint parsing.
#include "client/router.hpp"

#include <gtest/gtest.h>

#include <map>

namespace bounce::client {
namespace {

// Vectors computed by an independent implementation of docs/scaling.md's definition; the Python
// client's tests hold the same ones.
TEST(Rendezvous, WeightsMatchTheDefinition) {
    EXPECT_EQ(rendezvous_weight("127.0.0.1:7878", "cornell"), 0xdad35017d9228fd2ull);
    EXPECT_EQ(rendezvous_weight("[::1]:7878", "cornell"), 0x0e3b98ba5962e6a9ull);
    EXPECT_EQ(rendezvous_weight("10.0.0.2:7878", "atrium"), 0x9d0e179c8bfeefd2ull);
    EXPECT_EQ(rendezvous_weight("", ""), 0x25fc6dd36ce04b20ull);
    EXPECT_EQ(rendezvous_weight("127.0.0.1:7878", ""), 0x172b0fb6438f5164ull);
}

TEST(Rendezvous, TheSeparatorKeepsKeyAndSceneApart) {
    EXPECT_NE(rendezvous_weight("ab", "c"), rendezvous_weight("a", "bc"));
}

std::vector<Endpoint> three_daemons() { return {{"10.0.0.1", 7878}, {"10.0.0.2", 7878}, {"10.0.0.3", 7878}}; }

// 3000 scenes over 3 daemons: each count is binomial(3000, 1/3), standard deviation 25.8; five
// deviations (±129) fail a fair hash with probability under 1e-6.
TEST(Rendezvous, SpreadsScenesEvenly) {
    const auto endpoints = three_daemons();
    std::map<std::string, int> counts;
    for (int i = 0; i < 3000; ++i) ++counts[rendezvous_order(endpoints, "scene-" + std::to_string(i)).front().to_string()];
    ASSERT_EQ(counts.size(), 3u);
    for (const auto& [endpoint, count] : counts) EXPECT_NEAR(count, 1000, 129) << endpoint;
}

// The point of rendezvous hashing: when a daemon goes, only its scenes move, each to the daemon
// that was second in its order; every other scene stays where it is resident.
TEST(Rendezvous, OnlyTheScenesOfALostDaemonMove) {
    const auto all = three_daemons();
    const std::vector<Endpoint> without_second = {all[0], all[2]};
    int moved = 0;
    for (int i = 0; i < 3000; ++i) {
        const std::string scene = "scene-" + std::to_string(i);
        const auto before = rendezvous_order(all, scene);
        const Endpoint after = rendezvous_order(without_second, scene).front();
        if (before.front() == all[1]) {
            EXPECT_EQ(after, before[1]) << scene;
            ++moved;
        } else {
            EXPECT_EQ(after, before.front()) << scene;
        }
    }
    EXPECT_GT(moved, 0);
}

TEST(Rendezvous, OrderIsAPermutationAndIndependentOfListOrder) {
    auto endpoints = three_daemons();
    const auto order = rendezvous_order(endpoints, "atrium");
    std::reverse(endpoints.begin(), endpoints.end());
    EXPECT_EQ(rendezvous_order(endpoints, "atrium"), order);
    ASSERT_EQ(order.size(), 3u);
    EXPECT_NE(order[0], order[1]);
    EXPECT_NE(order[1], order[2]);
    EXPECT_NE(order[0], order[2]);
}

TEST(Endpoints, ParseHostsPortsAndBracketedIpv6) {
    EXPECT_EQ(Endpoint::parse("render-0.bounce:7000"), (Endpoint{"render-0.bounce", 7000}));
    EXPECT_EQ(Endpoint::parse("[::1]:7878"), (Endpoint{"::1", 7878}));
    EXPECT_EQ((Endpoint{"::1", 7878}).to_string(), "[::1]:7878");
    EXPECT_EQ((Endpoint{"127.0.0.1", 1}).to_string(), "127.0.0.1:1");
    EXPECT_THROW(Endpoint::parse("no-port"), std::invalid_argument);
    EXPECT_THROW(Endpoint::parse(":7878"), std::invalid_argument);
    EXPECT_THROW(Endpoint::parse("[]:7878"), std::invalid_argument);
    EXPECT_THROW(Endpoint::parse("host:70000"), std::invalid_argument);
    EXPECT_THROW(Endpoint::parse("host:x"), std::invalid_argument);
}

// Every entry resolves to numeric addresses, so that all clients key a daemon alike; the same
// daemon named twice is one endpoint.
TEST(Endpoints, ResolveToNumericAddressesWithoutDuplicates) {
    const auto endpoints = resolve_endpoints("127.0.0.1:7001,localhost:7002,127.0.0.1:7001");
    std::vector<std::string> keys;
    for (const auto& endpoint : endpoints) keys.push_back(endpoint.to_string());
    EXPECT_NE(std::find(keys.begin(), keys.end(), "127.0.0.1:7001"), keys.end());
    EXPECT_EQ(std::count(keys.begin(), keys.end(), "127.0.0.1:7001"), 1);
    // localhost gives 127.0.0.1 only, even where it also resolves to ::1.
    EXPECT_EQ(keys, (std::vector<std::string>{"127.0.0.1:7001", "127.0.0.1:7002"}));
    EXPECT_THROW(resolve_endpoints("127.0.0.1:7001,,127.0.0.1:7002"), std::invalid_argument);
    EXPECT_THROW(resolve_endpoints("no-such-host.invalid:7878"), ConnectionError);
}

TEST(Router, NeedsAnEndpoint) { EXPECT_THROW(Router({}), std::invalid_argument); }

}  // namespace
}  // namespace bounce::client
