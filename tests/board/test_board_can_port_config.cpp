// The board CAN port's config, its kernel filters and its failure to open, on the host (whose kernel may have
// no CAN at all: opening must then fail with a message, never leave a half-open port).
#include <linux/can.h>

#include <catch2/catch.hpp>
#include <set>
#include <string>

#include "lever/board/board_can_port.hpp"
#include "lever/board/interface_name.hpp"
#include "lever/protocol/messages.hpp"

using lever::board::BoardCanPort;
using lever::board::BoardCanPortConfig;
using lever::board::CanFilter;
using lever::board::lever_pair_filters;

namespace {

// The kernel's test (af_can.c): a frame passes a filter when its id, flags included, matches under the mask.
bool passes(const CanFilter& f, std::uint32_t can_id) { return (can_id & f.mask) == (f.id & f.mask); }

bool any_passes(std::uint8_t pair, std::uint32_t can_id) {
  for (const auto& f : lever_pair_filters(pair)) {
    if (passes(f, can_id)) return true;
  }
  return false;
}

bool contains(const std::vector<std::string>& problems, const std::string& start) {
  for (const auto& p : problems) {
    if (p.rfind(start, 0) == 0) return true;
  }
  return false;
}

}  // namespace

TEST_CASE("a pair's filters pass its seven ids and no other classic frame", "[board_can]") {
  for (std::uint8_t pair = 0; pair < lever::protocol::kPairCount; ++pair) {
    using lever::protocol::Role;
    const std::set<std::uint32_t> own = {lever::protocol::command_id(pair),
                                         lever::protocol::motion_id(pair),
                                         lever::protocol::force_id(pair),
                                         lever::protocol::energy_id(pair, Role::hsi),
                                         lever::protocol::energy_id(pair, Role::top),
                                         lever::protocol::heartbeat_id(pair, Role::hsi),
                                         lever::protocol::heartbeat_id(pair, Role::top)};
    std::size_t passed = 0;
    for (std::uint32_t id = 0; id <= CAN_SFF_MASK; ++id) {
      const bool pass = any_passes(pair, id);
      CHECK(pass == (own.count(id) == 1));
      passed += pass ? 1 : 0;
    }
    CHECK(passed == 7);
  }
}

TEST_CASE("extended and remote frames with a pair's ids do not pass", "[board_can]") {
  const std::uint32_t motion = lever::protocol::motion_id(3);
  CHECK(any_passes(3, motion));
  CHECK_FALSE(any_passes(3, motion | CAN_EFF_FLAG));
  CHECK_FALSE(any_passes(3, motion | CAN_RTR_FLAG));
  CHECK_FALSE(any_passes(3, (motion << 18) | CAN_EFF_FLAG));  // the same 11 bits as an extended id's base
}

TEST_CASE("the port's config is checked field by field", "[board_can]") {
  BoardCanPortConfig good;
  CHECK(good.validate().empty());

  BoardCanPortConfig bad;
  bad.interface = "";
  bad.pair = 16;
  bad.link_retry_ms = 0;
  const auto problems = bad.validate();
  CHECK(problems.size() == 3);
  CHECK(contains(problems, "interface: "));
  CHECK(contains(problems, "pair: 16"));
  CHECK(contains(problems, "link_retry_ms: "));

  BoardCanPortConfig long_name;
  long_name.interface = "can-much-too-long";
  long_name.link_retry_max_ms = 10;
  const auto more = long_name.validate();
  CHECK(contains(more, "interface: \"can-much-too-long\""));
  CHECK(contains(more, "link_retry_max_ms: 10"));
}

TEST_CASE("interface names as the kernel takes them (dev_valid_name), and no '%'", "[board_can]") {
  using lever::board::interface_name_problem;
  using namespace std::string_literals;
  for (const std::string& good : {"can0"s, "vcan1"s, "fifteen-bytes-x"s, "..."s, ".can"s, "-x"s, "can\x01"s,
                                  "c\xC3\xA4n0"s /* can with a-umlaut: C3 A4 */, "a,b=c"s}) {
    INFO("'" << good << "'");
    CHECK_FALSE(interface_name_problem(good).has_value());
  }
  for (const std::string& bad :
       {""s, "sixteen-bytes-xx"s, "."s, ".."s, "a/b"s, "a:b"s, "a b"s, "a\tb"s, "a\nb"s, "a\vb"s, "a\fb"s, "a\rb"s,
        "\xC3\xA0"s /* a-grave: C3 A0, 0xA0 is the kernel's space */, "can%d"s, "a\0b"s}) {
    INFO("'" << bad << "'");
    CHECK(interface_name_problem(bad).has_value());
  }
  CHECK(*interface_name_problem("a/b") == "contains '/', which the kernel refuses in an interface name");
  CHECK(*interface_name_problem("a\tb") == "contains \\x09, which the kernel refuses in an interface name");
  BoardCanPortConfig c;
  c.interface = "can:0";
  CHECK(contains(c.validate(), "interface: \"can:0\": contains ':'"));
}

TEST_CASE("a port that cannot be opened is an error naming the interface", "[board_can]") {
  BoardCanPortConfig config;
  config.interface = "lever-nocan";  // no such interface here, whether or not this kernel has CAN
  const auto port = BoardCanPort::open(config);
  REQUIRE_FALSE(port.ok());
  CHECK(port.error().message.rfind("lever-nocan: ", 0) == 0);
  CHECK(port.error().errno_value != 0);

  config.pair = 99;
  const auto invalid = BoardCanPort::open(config);
  REQUIRE_FALSE(invalid.ok());
  CHECK(invalid.error().message.find("pair: 99") != std::string::npos);
}
