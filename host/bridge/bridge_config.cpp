#include "bridge_config.hpp"

#include <arpa/inet.h>
#include <fmt/format.h>
#include <net/if.h>
#include <netinet/in.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "lever/platform/interface_name.hpp"
#include "lever/platform/udp_socket.hpp"
#include "lever/program/config_file.hpp"
#include "shown_value.hpp"

#define TOML_EXCEPTIONS 1
#include <toml++/toml.h>

namespace lever::bridge {
namespace {

// Far beyond any real configuration (a few hundred bytes), and small enough to read whole.
// A value from the file, as the user wrote it, cut short: it is echoed into a one-line message.
std::string shown(const toml::node& node) {
  std::string text;
  if (const auto s = node.value_exact<std::string>()) {
    text = fmt::format("'{}'", *s);
  } else if (const auto i = node.value_exact<std::int64_t>()) {
    text = fmt::format("{}", *i);
  } else if (const auto d = node.value_exact<double>()) {
    text = fmt::format("{}", *d);
  } else if (const auto b = node.value_exact<bool>()) {
    text = *b ? "true" : "false";
  } else {
    text = fmt::format("a {}", node.type() == toml::node_type::table ? "table" : "list");
  }
  return shown_value(text);
}

}  // namespace

void load_config_file(const std::filesystem::path& file, BridgeConfig& c) {
  const auto read = program::read_config_file(file.string());
  if (!read.error.empty()) throw std::invalid_argument(read.error);
  toml::table t;
  try {
    t = toml::parse(read.text, file.string());
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
                                                "site_id",
                                                "peer_site_id",
                                                "realtime_priority"};
  for (const auto& [key, value] : t) {
    bool known = false;
    for (const auto k : kKnown) known = known || key.str() == k;
    if (!known) throw fail(shown_value(key.str()), "unknown key");
  }
  auto text = [&](std::string_view key) -> std::optional<std::string> {
    const auto node = t[key];
    if (!node) return std::nullopt;
    const auto s = node.value_exact<std::string>();
    if (!s) throw fail(key, fmt::format("expected a string, got {}", shown(*node.node())));
    if (s->empty()) throw fail(key, "must not be empty");
    return *s;
  };
  // A real number: finite and in [low, high]. NaN fails every comparison, so the test is written to refuse it.
  auto real = [&](std::string_view key, double low, double high, std::string_view what) -> std::optional<double> {
    const auto node = t[key];
    if (!node) return std::nullopt;
    const auto v = node.value<double>();  // an integer converts
    if (!v || !std::isfinite(*v) || !(low <= *v && *v <= high)) {
      throw fail(key, fmt::format("must be {}, got {}", what, shown(*node.node())));
    }
    return *v;
  };
  // An integer: a TOML integer, or a float with no fraction (1e6).
  auto integer = [&](std::string_view key, std::int64_t low, std::int64_t high) -> std::optional<std::int64_t> {
    const auto node = t[key];
    if (!node) return std::nullopt;
    std::optional<std::int64_t> value = node.value_exact<std::int64_t>();
    if (const auto d = node.value_exact<double>();
        !value && d && std::isfinite(*d) && std::trunc(*d) == *d && std::fabs(*d) < 9e15) {
      value = static_cast<std::int64_t>(*d);
    }
    if (!value || *value < low || *value > high) {
      throw fail(key, fmt::format("must be an integer from {} to {}, got {}", low, high, shown(*node.node())));
    }
    return value;
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
  // Relative to the configuration file: the working directory of a service is not where its files are.
  auto path = [&](const std::string& p) {
    const std::filesystem::path given(p);
    return given.is_absolute() ? given : file.parent_path() / given;
  };
  if (const auto v = text("can")) c.can_interface = *v;
  if (const auto v = text("bind")) c.bind = *v;
  if (const auto v = text("peer")) c.peer = *v;
  if (const auto v = text("key")) c.key_file = path(*v);
  if (const auto v = allow("allow")) c.allow_to_network = c.allow_from_network = *v;
  if (const auto v = allow("allow_to_network")) c.allow_to_network = *v;
  if (const auto v = allow("allow_from_network")) c.allow_from_network = *v;
  if (const auto v = text("record")) c.record = path(*v);
  if (const auto v = text("record_network_interface")) c.record_network_interface = *v;
  // 1 TB: beyond any disk this writes to, and far from overflowing the byte count.
  if (const auto v = real("record_rotate_mb", 0, 1e6, "a size in MB from 0 (never rotate) to 1000000")) {
    c.record_rotate_bytes = static_cast<std::uint64_t>(*v * 1024 * 1024);
  }
  if (const auto v = integer("record_keep_files", 1, 1000)) c.record_keep_files = static_cast<int>(*v);
  if (const auto node = t["stats_json"]) {
    const auto b = node.value_exact<bool>();
    if (!b) throw fail("stats_json", fmt::format("expected true or false, got {}", shown(*node.node())));
    c.stats_json = *b;
  }
  if (const auto v = real("stats_interval_s", 0.01, 3600, "a time in seconds from 0.01 to 3600")) {
    c.stats_interval_s = *v;
  }
  if (const auto v = real("probe_interval_s", 0.01, 3600, "a time in seconds from 0.01 to 3600")) {
    c.probe_interval_s = *v;
  }
  // Classic CAN's range of bit rates; a bit rate is a whole number of bits per second.
  if (const auto v = integer("can_bitrate", 10'000, 1'000'000)) c.can_bitrate = static_cast<double>(*v);
  if (const auto v = integer("site_id", 0, 255)) c.site_id = static_cast<std::uint8_t>(*v);
  if (const auto v = integer("peer_site_id", 0, 255)) c.peer_site_id = static_cast<std::uint8_t>(*v);
  if (const auto v = integer("realtime_priority", 0, 99)) c.realtime_priority = static_cast<int>(*v);
}

namespace {

bool is_unspecified(const platform::SocketAddress& a) {
  if (a.family() == AF_INET) {
    return reinterpret_cast<const sockaddr_in*>(&a.storage)->sin_addr.s_addr == htonl(INADDR_ANY);
  }
  const auto& v6 = reinterpret_cast<const sockaddr_in6*>(&a.storage)->sin6_addr;
  return IN6_IS_ADDR_UNSPECIFIED(&v6);
}

bool is_loopback(const platform::SocketAddress& a) {
  if (a.family() == AF_INET) {
    return (ntohl(reinterpret_cast<const sockaddr_in*>(&a.storage)->sin_addr.s_addr) >> 24) == 127;
  }
  const auto& v6 = reinterpret_cast<const sockaddr_in6*>(&a.storage)->sin6_addr;
  return IN6_IS_ADDR_LOOPBACK(&v6);
}

// Why `a` cannot be one unicast peer, or nullptr.
const char* not_unicast(const platform::SocketAddress& a) {
  if (a.family() == AF_INET) {
    const std::uint32_t ip = ntohl(reinterpret_cast<const sockaddr_in*>(&a.storage)->sin_addr.s_addr);
    if (ip == INADDR_BROADCAST) return "a broadcast address";
    if ((ip >> 28) == 0xE) return "a multicast address";
    if (ip == INADDR_ANY) return "the unspecified address (0.0.0.0)";
    return nullptr;
  }
  const auto& v6 = reinterpret_cast<const sockaddr_in6*>(&a.storage)->sin6_addr;
  if (IN6_IS_ADDR_MULTICAST(&v6)) return "a multicast address";
  if (IN6_IS_ADDR_UNSPECIFIED(&v6)) return "the unspecified address (::)";
  return nullptr;
}

std::uint16_t port_of(const platform::SocketAddress& a) {
  return ntohs(a.family() == AF_INET ? reinterpret_cast<const sockaddr_in*>(&a.storage)->sin_port
                                     : reinterpret_cast<const sockaddr_in6*>(&a.storage)->sin6_port);
}

std::string cut(const std::string& s, std::size_t limit = 80) { return shown_value(s, limit); }

// The recording appends to a regular file of its own and renames it when it rotates: a device, a symlink, a
// directory or the key itself must never be that file.
void check_record_path(const std::filesystem::path& record, const std::filesystem::path& key_file) {
  const std::string shown_path = cut(record.string());
  struct stat st {};
  if (::lstat(record.c_str(), &st) == 0) {
    if (!S_ISREG(st.st_mode)) {
      throw std::invalid_argument(fmt::format("record '{}': {}; the recording is a regular file of its own", shown_path,
                                              program::file_kind(st.st_mode)));
    }
    struct stat key {};
    if (!key_file.empty() && ::stat(key_file.c_str(), &key) == 0 && key.st_dev == st.st_dev &&
        key.st_ino == st.st_ino) {
      throw std::invalid_argument(fmt::format("record '{}' is the key file", shown_path));
    }
    return;
  }
  if (errno != ENOENT) {
    throw std::invalid_argument(fmt::format("record '{}': {}", shown_path, std::strerror(errno)));
  }
  const auto parent = record.has_parent_path() ? record.parent_path() : std::filesystem::path(".");
  if (::stat(parent.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
    throw std::invalid_argument(
        fmt::format("record '{}': the directory '{}' does not exist", shown_path, cut(parent.string())));
  }
}

}  // namespace

void validate(const BridgeConfig& c) {
  auto fail = [](std::string message) { return std::invalid_argument(std::move(message)); };
  for (const auto& [value, name] : {std::pair{&c.can_interface, "can"}, {&c.bind, "bind"}, {&c.peer, "peer"}}) {
    if (value->empty()) throw fail(fmt::format("--{0} (key '{0}') is required (see --help)", name));
  }
  if (const auto problem = platform::interface_name_problem(c.can_interface))
    throw fail(fmt::format("can '{}': not an interface name: {}", cut(c.can_interface), *problem));
  std::string error;
  const auto bind = platform::parse_socket_address(c.bind, error);
  if (!bind) throw fail("bind " + cut(error, 200));
  const auto peer = platform::parse_socket_address(c.peer, error);
  if (!peer) throw fail("peer " + cut(error, 200));
  if (port_of(*bind) == 0) {
    throw fail(fmt::format("bind '{}': port 0 would be a random port, which the peer cannot know", cut(c.bind)));
  }
  if (port_of(*peer) == 0) throw fail(fmt::format("peer '{}': port 0 is no port a peer listens on", cut(c.peer)));
  if (const char* why = not_unicast(*peer)) {
    throw fail(fmt::format("peer '{}': {}; a bridge talks to one peer, at its unicast address", cut(c.peer), why));
  }
  if (const char* why = not_unicast(*bind); why && !is_unspecified(*bind)) {
    throw fail(fmt::format("bind '{}': {}; bind to a local unicast address or the unspecified one", cut(c.bind), why));
  }
  if (bind->family() != peer->family()) {
    throw fail(fmt::format("bind '{}' and peer '{}' are of different address families (IPv4 and IPv6)", cut(c.bind),
                           cut(c.peer)));
  }
  // Our own address: the same, or a loopback address on our port when we listen on every address.
  if (*bind == *peer || (is_unspecified(*bind) && is_loopback(*peer) && port_of(*bind) == port_of(*peer))) {
    throw fail(fmt::format("peer '{}' is this bridge's own address (bind '{}'): the peer is the other site's bridge",
                           cut(c.peer), cut(c.bind)));
  }
  if (c.site_id && c.peer_site_id && *c.site_id == *c.peer_site_id) {
    throw fail(fmt::format("site_id and peer_site_id are both {}: each end needs its own id", *c.site_id));
  }
  if (c.record && c.record->empty()) throw fail("record: the path is empty");
  if (c.record) check_record_path(*c.record, c.key_file);
}

}  // namespace lever::bridge
