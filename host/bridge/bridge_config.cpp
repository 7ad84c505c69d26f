#include "bridge_config.hpp"

#include <fmt/format.h>

#define TOML_EXCEPTIONS 1
#include <toml++/toml.h>

namespace lever::bridge {

void load_config_file(const std::filesystem::path& file, BridgeConfig& c) {
  toml::table t;
  try {
    t = toml::parse_file(file.string());
  } catch (const toml::parse_error& e) {
    throw std::invalid_argument(fmt::format("{}:{}: {}", file.string(), e.source().begin.line, e.description()));
  }
  auto fail = [&](std::string_view key, std::string_view problem) {
    return std::invalid_argument(fmt::format("{}: key '{}': {}", file.string(), key, problem));
  };
  static constexpr std::string_view kKnown[] = {"can",
                                                "bind",
                                                "peer",
                                                "key",
                                                "allow",
                                                "allow_to_network",
                                                "allow_from_network",
                                                "record",
                                                "record_network_interface",
                                                "record_rotate_mb",
                                                "record_keep_files",
                                                "stats_json",
                                                "stats_interval_s",
                                                "probe_interval_s",
                                                "can_bitrate",
                                                "site_id"};
  for (const auto& [key, value] : t) {
    bool known = false;
    for (const auto k : kKnown) known = known || key.str() == k;
    if (!known) throw fail(key.str(), "unknown key");
  }
  auto text = [&](std::string_view key) -> std::optional<std::string> {
    const auto node = t[key];
    if (!node) return std::nullopt;
    if (const auto s = node.value<std::string>()) return *s;
    throw fail(key, "expected a string");
  };
  auto number = [&](std::string_view key) -> std::optional<double> {
    const auto node = t[key];
    if (!node) return std::nullopt;
    if (const auto v = node.value<double>()) return *v;
    throw fail(key, "expected a number");
  };
  auto allow = [&](std::string_view key) -> std::optional<AllowList> {
    const auto s = text(key);
    if (!s) return std::nullopt;
    try {
      return AllowList::parse(*s);
    } catch (const std::invalid_argument& e) {
      throw fail(key, e.what());
    }
  };
  if (const auto v = text("can")) c.can_interface = *v;
  if (const auto v = text("bind")) c.bind = *v;
  if (const auto v = text("peer")) c.peer = *v;
  if (const auto v = text("key")) c.key_file = *v;
  if (const auto v = allow("allow")) c.allow_to_network = c.allow_from_network = *v;
  if (const auto v = allow("allow_to_network")) c.allow_to_network = *v;
  if (const auto v = allow("allow_from_network")) c.allow_from_network = *v;
  if (const auto v = text("record")) c.record = *v;
  if (const auto v = text("record_network_interface")) c.record_network_interface = *v;
  if (const auto v = number("record_rotate_mb")) {
    if (*v < 0) throw fail("record_rotate_mb", "must not be negative");
    c.record_rotate_bytes = static_cast<std::uint64_t>(*v * 1024 * 1024);
  }
  if (const auto v = number("record_keep_files")) {
    if (*v < 1 || *v > 1000) throw fail("record_keep_files", "must be 1 to 1000");
    c.record_keep_files = static_cast<int>(*v);
  }
  if (const auto node = t["stats_json"]) {
    if (const auto b = node.value<bool>()) {
      c.stats_json = *b;
    } else {
      throw fail("stats_json", "expected true or false");
    }
  }
  if (const auto v = number("stats_interval_s")) {
    if (*v < 0.01 || *v > 3600) throw fail("stats_interval_s", "must be 0.01 to 3600");
    c.stats_interval_s = *v;
  }
  if (const auto v = number("probe_interval_s")) {
    if (*v < 0.01 || *v > 3600) throw fail("probe_interval_s", "must be 0.01 to 3600");
    c.probe_interval_s = *v;
  }
  if (const auto v = number("can_bitrate")) {
    if (*v < 10e3 || *v > 1e6) throw fail("can_bitrate", "must be 10000 to 1000000 (classic CAN)");
    c.can_bitrate = *v;
  }
  if (const auto v = number("site_id")) {
    if (*v < 0 || *v > 255 || *v != static_cast<int>(*v)) throw fail("site_id", "must be an integer 0 to 255");
    c.site_id = static_cast<std::uint8_t>(*v);
  }
}

}  // namespace lever::bridge
