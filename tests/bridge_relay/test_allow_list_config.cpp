// lever-bridge's allow-lists and configuration file.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "allow_list.hpp"
#include "bridge_config.hpp"
#include "bridge_stats.hpp"

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
  CHECK(a.describe() == "0x080-0x08F,0x100-0x11F,0x700-0x71F");
  CHECK_FALSE(a.allows(0x000));
  CHECK_FALSE(a.allows(0x123));
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
                    Catch::Contains("key 'cann': unknown key"));
  CHECK_THROWS_WITH(load_config_file(write_temp("lever-bridge-bad2.toml", "site_id = 300\n"), d),
                    Catch::Contains("'site_id'"));
  CHECK_THROWS_WITH(load_config_file(write_temp("lever-bridge-bad3.toml", "can = 5\n"), d),
                    Catch::Contains("expected a string"));
  CHECK_THROWS_WITH(load_config_file(write_temp("lever-bridge-bad4.toml", "can = \"vcan0\nbind=\n"), d),
                    Catch::Contains("lever-bridge-bad4.toml:"));
  CHECK_THROWS_WITH(load_config_file(write_temp("lever-bridge-bad5.toml", "allow = \"0x900\"\n"), d),
                    Catch::Contains("beyond 11 bits"));
}

TEST_CASE("latency percentiles come out of the histogram within a bucket", "[bridge][stats]") {
  LatencyHistogram h;
  CHECK_FALSE(h.percentile(0.5).has_value());
  for (int i = 1; i <= 1000; ++i) h.add(i);  // 1..1000 us
  CHECK(*h.percentile(0.5) == Approx(500).epsilon(0.06));
  CHECK(*h.percentile(0.99) == Approx(990).epsilon(0.06));
  CHECK(h.max() == 1000);
}
