// lever-bridge's allow-lists and configuration file.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "allow_list.hpp"
#include "bridge_config.hpp"
#include "bridge_stats.hpp"
#include "lever/program/config_schema.hpp"
#include "lever/protocol/messages.hpp"

using namespace lever::bridge;

TEST_CASE("allow-lists parse ids and ranges, and say what is wrong", "[bridge][allow]") {
  const auto a = AllowList::parse("0x100-0x1FF, 0x700 ,7ff");
  CHECK(a.allows(0x100));
  CHECK(a.allows(0x1FF));
  CHECK_FALSE(a.allows(0x200));
  CHECK(a.allows(0x700));
  CHECK(a.allows(0x7FF));
  CHECK_FALSE(a.allows(0x800));  // not an 11-bit id at all
  CHECK(a.count() == 258u);
  CHECK(a.describe() == "0x100-0x1FF,0x700,0x7FF");
  CHECK_THROWS_WITH(AllowList::parse(""), Catch::Contains("empty"));
  CHECK_THROWS_WITH(AllowList::parse("0x100,,0x200"), Catch::Contains("empty item"));
  CHECK_THROWS_WITH(AllowList::parse("0x10G"), Catch::Contains("'10G' is not a hexadecimal id"));
  CHECK_THROWS_WITH(AllowList::parse("0x800"), Catch::Contains("beyond 11 bits"));
  CHECK_THROWS_WITH(AllowList::parse("0x200-0x100"), Catch::Contains("backwards"));
}

TEST_CASE("the default allow-list is the lever protocol's ids and nothing else", "[bridge][allow]") {
  const auto a = AllowList::lever_protocol();
  CHECK(a.describe() == "0x080-0x08F,0x100-0x15F,0x700-0x71F");
  CHECK_FALSE(a.allows(0x000));
  CHECK(a.allows(0x123));  // an energy frame (pair 1, TOP)
  CHECK(a.allows(0x15F));  // a settings frame (pair 15, TOP)
  CHECK_FALSE(a.allows(0x160));
  // Every id the message set defines, and none it does not.
  for (std::uint32_t id = 0; id <= lever::protocol::kMaxStandardId; ++id) {
    lever::protocol::FrameAddress address;
    INFO(id);
    CHECK(a.allows(id) == (lever::protocol::classify(id, address) == lever::protocol::DecodeError::none));
  }
}

namespace {
std::filesystem::path write_temp(const std::string& name, const std::string& content) {
  const auto path = std::filesystem::temp_directory_path() / name;
  std::ofstream(path) << content;
  return path;
}
}  // namespace

TEST_CASE("the TOML config sets every option and rejects what it does not know", "[bridge][config]") {
  const auto good = write_temp("lever-bridge-good.toml", R"(
can = "vcan0"
bind = "127.0.0.1:5000"
peer = "[::1]:5001"
key = "/etc/lever/site.key"
allow_to_network = "0x100-0x10F"
allow_from_network = "0x110-0x11F"
record = "/var/log/lever.log"
record_rotate_mb = 2
stats_json = true
site_id = 7
)");
  BridgeConfig c;
  load_config_file(good, c);
  CHECK(c.can_interface == "vcan0");
  CHECK(c.peer == "[::1]:5001");
  CHECK(c.allow_to_network.describe() == "0x100-0x10F");
  CHECK(c.allow_from_network.describe() == "0x110-0x11F");
  CHECK(c.record_rotate_bytes == 2u * 1024 * 1024);
  CHECK(c.stats_json);
  REQUIRE(c.site_id);
  CHECK(*c.site_id == 7);

  BridgeConfig d;
  CHECK_THROWS_WITH(load_config_file(write_temp("lever-bridge-bad1.toml", "cann = \"vcan0\"\n"), d),
                    Catch::Contains("lever-bridge-bad1.toml: cann: unknown key"));
  CHECK_THROWS_WITH(load_config_file(write_temp("lever-bridge-bad2.toml", "site_id = 300\n"), d),
                    Catch::Contains("site_id: "));
  CHECK_THROWS_WITH(load_config_file(write_temp("lever-bridge-bad3.toml", "can = 5\n"), d),
                    Catch::Contains("can: must be a string, got an integer"));
  CHECK_THROWS_WITH(load_config_file(write_temp("lever-bridge-bad4.toml", "can = \"vcan0\nbind=\n"), d),
                    Catch::Contains("lever-bridge-bad4.toml:"));
  CHECK_THROWS_WITH(load_config_file(write_temp("lever-bridge-bad5.toml", "allow = \"0x900\"\n"), d),
                    Catch::Contains("beyond 11 bits"));
}

TEST_CASE("config numbers: NaN, infinities and fractions are refused at load, naming key and value",
          "[bridge][config]") {
  const auto refused = [](const std::string& content, const std::string& message) {
    BridgeConfig c;
    CAPTURE(content);
    CHECK_THROWS_WITH(load_config_file(write_temp("lever-bridge-number.toml", content), c), Catch::Contains(message));
  };
  refused("stats_interval_s = nan\n", "stats_interval_s: must be a number of s in [0.01, 3600], got nan");
  refused("probe_interval_s = inf\n", "probe_interval_s: must be a number of s in [0.01, 3600], got inf");
  refused("probe_interval_s = 0.001\n", "got 0.001");
  refused("record_rotate_mb = nan\n", "record_rotate_mb: ");
  refused("record_rotate_mb = -1\n", "got -1");
  refused("record_rotate_mb = 1e300\n", "got 1e+300");
  refused("record_keep_files = 2.5\n", "record_keep_files: must be a whole number in [1, 1000], got 2.5");
  refused("record_keep_files = nan\n", "got nan");
  refused("can_bitrate = 500000.5\n", "can_bitrate: must be a whole number in [10000, 1000000], got 500000.5");
  refused("can_bitrate = nan\n", "can_bitrate: ");
  refused("site_id = 2.5\n", "site_id: must be a whole number in [0, 255], got 2.5");
  refused("site_id = -1\n", "got -1");
  refused("peer_site_id = 256\n", "peer_site_id: must be a whole number in [0, 255], got 256");
  refused("realtime_priority = -1\n", "realtime_priority: must be a whole number in [0, 99], got -1");
  refused("realtime_priority = 100\n", "got 100");
  refused("site_id = \"7\"\n", "site_id: must be a whole number in [0, 255], got a string");
  refused("stats_json = 1\n", "stats_json: must be true or false, got an integer");
  refused("can = \"\"\n", "can: must not be empty");
  refused("allow = \"\"\n", "allow: must not be empty");

  BridgeConfig c;
  load_config_file(write_temp("lever-bridge-numbers-ok.toml",
                              "can_bitrate = 5e5\nrecord_keep_files = 3.0\nrealtime_priority = 70\npeer_site_id = 1\n"),
                   c);
  CHECK(c.can_bitrate == 500000);  // a float with no fraction is an integer
  CHECK(c.record_keep_files == 3);
  CHECK(c.realtime_priority == 70);
  REQUIRE(c.peer_site_id);
  CHECK(*c.peer_site_id == 1);
  // The ends of each range are in it.
  load_config_file(write_temp("lever-bridge-ends.toml", "site_id = 255\npeer_site_id = 0\nrealtime_priority = 99\n"),
                   c);
  CHECK(c.site_id == std::uint8_t{255});
  CHECK(c.peer_site_id == std::uint8_t{0});
  CHECK(c.realtime_priority == 99);

  BridgeConfig defaults;
  CHECK(defaults.realtime_priority == 40);  // real time unless told otherwise
  load_config_file(write_temp("lever-bridge-no-realtime.toml", "realtime_priority = 0\n"), defaults);
  CHECK(defaults.realtime_priority == 0);  // 0: normal scheduling
}

TEST_CASE("config allow: the two directions' keys override it, wherever they stand in the file", "[bridge][config]") {
  BridgeConfig c;
  load_config_file(write_temp("lever-bridge-allow.toml", "allow_to_network = \"0x100\"\nallow = \"0x200-0x201\"\n"), c);
  CHECK(c.allow_to_network.describe() == "0x100");
  CHECK(c.allow_from_network.describe() == "0x200-0x201");
  BridgeConfig both;
  load_config_file(write_temp("lever-bridge-allow.toml", "allow = \"0x300\"\n"), both);
  CHECK(both.allow_to_network.describe() == "0x300");
  CHECK(both.allow_from_network.describe() == "0x300");
}

TEST_CASE("config: a refused file changes nothing, and the printed schema reads back", "[bridge][config]") {
  BridgeConfig c;
  CHECK_THROWS(load_config_file(write_temp("lever-bridge-half.toml", "can = \"vcan0\"\nsite_id = 300\n"), c));
  CHECK(c.can_interface.empty());  // the key before the problem was not applied

  load_config_file(write_temp("lever-bridge-print.toml", R"(
can = "vcan0"
bind = "127.0.0.1:5000"
peer = "127.0.0.1:5001"
key = "/etc/lever/site.key"
allow_from_network = "0x110-0x11F"
record_rotate_mb = 2.5
can_bitrate = 5e5
peer_site_id = 9
)"),
                   c);
  const auto printed = schema_for(c).print();
  CHECK_THAT(printed, Catch::Contains("# site_id (unset)"));
  CHECK_THAT(printed, Catch::Contains("# allow (unset)"));  // the two directions differ
  CHECK_THAT(printed, Catch::Contains("record_rotate_mb = 2.5  # MB: "));
  CHECK_THAT(printed, Catch::Contains("can_bitrate = 500000  # bit/s: "));
  BridgeConfig again;
  load_config_file(write_temp("lever-bridge-printed.toml", printed), again);
  CHECK(schema_for(again).print() == printed);
  CHECK(again.record_rotate_bytes == c.record_rotate_bytes);
  CHECK(schema_for(again).value_text("key") == "/etc/lever/site.key");
  CHECK(schema_for(again).value_text("site_id") == "");
}

TEST_CASE("config paths are relative to the configuration file", "[bridge][config]") {
  const auto dir = std::filesystem::temp_directory_path() / "lever-bridge-relative";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "bridge.toml") << "key = \"site.key\"\nrecord = \"logs/a.log\"\n";
  BridgeConfig c;
  load_config_file(dir / "bridge.toml", c);
  CHECK(c.key_file == dir / "site.key");
  REQUIRE(c.record);
  CHECK(*c.record == dir / "logs/a.log");
  std::ofstream(dir / "bridge.toml") << "key = \"/etc/lever/site.key\"\n";
  load_config_file(dir / "bridge.toml", c);
  CHECK(c.key_file == "/etc/lever/site.key");
}

TEST_CASE("the merged configuration: addresses, interface name and site ids", "[bridge][config]") {
  const auto base = [] {
    BridgeConfig c;
    c.can_interface = "vcan0";
    c.bind = "127.0.0.1:5000";
    c.peer = "127.0.0.1:5001";
    return c;
  };
  CHECK_NOTHROW(validate(base()));
  const auto refused = [&](auto edit, const std::string& message) {
    BridgeConfig c = base();
    edit(c);
    CHECK_THROWS_WITH(validate(c), Catch::Contains(message));
  };
  refused([](BridgeConfig& c) { c.peer = "127.0.0.1:0"; }, "peer '127.0.0.1:0': port 0");
  refused([](BridgeConfig& c) { c.bind = "127.0.0.1:0"; }, "bind '127.0.0.1:0': port 0");
  refused([](BridgeConfig& c) { c.peer = "255.255.255.255:5001"; }, "a broadcast address");
  refused([](BridgeConfig& c) { c.peer = "239.1.2.3:5001"; }, "a multicast address");
  refused([](BridgeConfig& c) { c.peer = "[ff02::1]:5001"; }, "a multicast address");
  refused([](BridgeConfig& c) { c.peer = "0.0.0.0:5001"; }, "the unspecified address");
  refused([](BridgeConfig& c) { c.peer = "127.0.0.1:5000"; }, "this bridge's own address");
  refused(
      [](BridgeConfig& c) {
        c.bind = "0.0.0.0:5000";
        c.peer = "127.0.0.1:5000";
      },
      "this bridge's own address");
  refused([](BridgeConfig& c) { c.peer = "[::1]:5001"; }, "different address families");
  refused([](BridgeConfig& c) { c.peer = "127.0.0.1:99999999999999999999999"; }, "port from 0 to 65535");
  refused([](BridgeConfig& c) { c.bind = "224.0.0.1:5000"; }, "bind '224.0.0.1:5000': a multicast address");
  refused([](BridgeConfig& c) { c.can_interface = "a-name-far-too-long"; }, "not an interface name");
  refused([](BridgeConfig& c) { c.can_interface = "../can0"; }, "not an interface name");
  refused([](BridgeConfig& c) { c.can_interface.clear(); }, "--can (key 'can') is required");
  refused(
      [](BridgeConfig& c) {
        c.site_id = 3;
        c.peer_site_id = 3;
      },
      "site_id and peer_site_id are both 3");
  BridgeConfig any = base();
  any.bind = "0.0.0.0:5000";  // every local address, a peer on another port of this host: fine
  CHECK_NOTHROW(validate(any));
}

TEST_CASE("latency percentiles come out of the histogram within a bucket", "[bridge][stats]") {
  LatencyHistogram h;
  CHECK_FALSE(h.percentile(0.5).has_value());
  for (int i = 1; i <= 1000; ++i) h.add(i);  // 1..1000 us
  CHECK(*h.percentile(0.5) == Approx(500).epsilon(0.06));
  CHECK(*h.percentile(0.99) == Approx(990).epsilon(0.06));
  CHECK(h.max() == 1000);
}

TEST_CASE("the network thread's histogram: each take is the interval since the last one", "[bridge][stats]") {
  SharedLatencyHistogram shared;
  CHECK(shared.take_interval().count() == 0);
  for (int i = 1; i <= 1000; ++i) shared.add(i);
  const LatencyHistogram first = shared.take_interval();
  CHECK(first.count() == 1000);
  CHECK(*first.percentile(0.5) == Approx(500).epsilon(0.06));
  CHECK(first.max() == 1000);
  for (int i = 0; i < 10; ++i) shared.add(20);
  const LatencyHistogram second = shared.take_interval();
  CHECK(second.count() == 10);  // the first thousand are not counted again
  CHECK(*second.percentile(0.99) == Approx(20).epsilon(0.06));
  CHECK(second.max() == 20);  // the maximum starts again
  CHECK(shared.take_interval().count() == 0);
}

TEST_CASE("counters: one writer's increments and a snapshot", "[bridge][stats]") {
  BridgeCounters c;
  ++c.to_network.frames;
  c.from_network.frames += 5;
  ++c.send_failures;
  c.send_failures += 2;
  const BridgeCounters snapshot = c;
  ++c.to_network.frames;
  CHECK(snapshot.to_network.frames.load() == 1);
  CHECK(c.to_network.frames.load() == 2);
  CHECK(snapshot.from_network.frames.load() == 5);
  CHECK(snapshot.send_failures.load() == 3);
}
