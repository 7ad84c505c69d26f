#include "bridge_config.hpp"

#include <arpa/inet.h>
#include <fmt/format.h>
#include <net/if.h>
#include <netinet/in.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "lever/board/interface_name.hpp"
#include "lever/board/udp_socket.hpp"
#include "lever/program/config_file.hpp"
#include "lever/program/config_schema.hpp"
#include "shown_value.hpp"

namespace lever::bridge {
namespace {

using program::ConfigSchema;

constexpr double kBytesPerMb = 1024.0 * 1024.0;

// Relative to the configuration file: the working directory of a service is not where its files are.
std::filesystem::path from_file(const std::string& text, const std::filesystem::path& file) {
  const std::filesystem::path given(text);
  return given.is_absolute() ? given : file.parent_path() / given;
}

// None yet is unset: "" would not load back.
std::optional<std::string> path_text(const std::filesystem::path& p) {
  if (p.empty()) return std::nullopt;
  return ConfigSchema::quoted(p.string());
}

void allow_keys(ConfigSchema& s, BridgeConfig& c) {
  const auto list = [](const AllowList& a) { return ConfigSchema::quoted(a.describe()); };
  // Before the two it sets, so that either overrides it wherever it stands in the file.
  s.parsed_text(
      "allow", "CAN ids allowed both ways, hex ids and ranges: 0x100-0x1FF,0x700 (the two keys below override it)",
      [&c](const std::string& t, const auto&) { c.allow_to_network = c.allow_from_network = AllowList::parse(t); },
      [&c, list]() -> std::optional<std::string> {
        if (c.allow_to_network.describe() != c.allow_from_network.describe()) return std::nullopt;
        return list(c.allow_to_network);
      });
  s.parsed_text(
      "allow_to_network", "CAN ids relayed from the bus to the peer",
      [&c](const std::string& t, const auto&) { c.allow_to_network = AllowList::parse(t); },
      [&c, list] { return list(c.allow_to_network); });
  s.parsed_text(
      "allow_from_network", "CAN ids relayed from the peer onto the bus",
      [&c](const std::string& t, const auto&) { c.allow_from_network = AllowList::parse(t); },
      [&c, list] { return list(c.allow_from_network); });
}

std::optional<std::string> load_rotate_mb(const toml::node& n, BridgeConfig& c) {
  double mb = 0.0;
  // 1 TB: beyond any disk this writes to, and far from overflowing the byte count.
  if (auto e = ConfigSchema::read_number(n, 0.0, 1e6, "MB", mb)) return e;
  c.record_rotate_bytes = static_cast<std::uint64_t>(mb * kBytesPerMb);
  return std::nullopt;
}

void record_keys(ConfigSchema& s, BridgeConfig& c) {
  s.parsed_text(
      "record", "candump -L log of every frame both ways; relative: from this file's directory",
      [&c](const std::string& t, const std::filesystem::path& file) { c.record = from_file(t, file); },
      [&c] { return c.record ? path_text(*c.record) : std::nullopt; });
  s.text("record_network_interface", c.record_network_interface,
         "interface name written for frames from the network (unset: the CAN interface)", ConfigSchema::Empty::refused);
  s.custom(
      "record_rotate_mb", "MB", "a new recording file at this size (0: never)",
      [&c](const toml::node& n) { return load_rotate_mb(n, c); },
      [&c] { return ConfigSchema::number_text(static_cast<double>(c.record_rotate_bytes) / kBytesPerMb); });
  s.integer("record_keep_files", c.record_keep_files, 1, 1000, "", "recording files kept when rotating");
}

}  // namespace

ConfigSchema schema_for(BridgeConfig& c) {
  using Empty = ConfigSchema::Empty;
  ConfigSchema s;
  s.text("can", c.can_interface, "SocketCAN interface, e.g. can0 or vcan0", Empty::refused);
  s.text("bind", c.bind, "local UDP address, HOST:PORT or [IPv6]:PORT", Empty::refused);
  s.text("peer", c.peer, "the other bridge's UDP address (one unicast address)", Empty::refused);
  s.parsed_text(
      "key", "pre-shared key file (64 hex digits, mode 0600); relative: from this file's directory",
      [&c](const std::string& t, const std::filesystem::path& file) { c.key_file = from_file(t, file); },
      [&c] { return path_text(c.key_file); });
  allow_keys(s, c);
  record_keys(s, c);
  s.boolean("stats_json", c.stats_json, "a JSON line of statistics every stats_interval_s");
  s.number("stats_interval_s", c.stats_interval_s, 0.01, 3600.0, "s", "statistics period");
  s.number("probe_interval_s", c.probe_interval_s, 0.01, 3600.0, "s", "clock-offset probe period");
  // Classic CAN's range of bit rates; a bit rate is a whole number of bits per second.
  s.integer("can_bitrate", c.can_bitrate, 10'000, 1'000'000, "bit/s", "the bus's bit rate, for bus_load only");
  s.integer("site_id", c.site_id, 0, 255, "", "this end's id in datagrams (unset: random at start-up)");
  s.integer("peer_site_id", c.peer_site_id, 0, 255, "",
            "datagrams carrying another sender id are refused (unset: any id but our own)");
  s.integer("realtime_priority", c.realtime_priority, 0, 99, "",
            "SCHED_FIFO priority of the two relay threads (0: normal scheduling)");
  return s;
}

void load_config_file(const std::filesystem::path& file, BridgeConfig& config) {
  // Into a copy: the keys before a problem would otherwise be applied and the rest not.
  BridgeConfig loaded = config;
  if (auto e = schema_for(loaded).load_file(file.string())) throw std::invalid_argument(*e);
  config = loaded;
}

namespace {

bool is_unspecified(const board::SocketAddress& a) {
  if (a.family() == AF_INET) {
    return reinterpret_cast<const sockaddr_in*>(&a.storage)->sin_addr.s_addr == htonl(INADDR_ANY);
  }
  const auto& v6 = reinterpret_cast<const sockaddr_in6*>(&a.storage)->sin6_addr;
  return IN6_IS_ADDR_UNSPECIFIED(&v6);
}

bool is_loopback(const board::SocketAddress& a) {
  if (a.family() == AF_INET) {
    return (ntohl(reinterpret_cast<const sockaddr_in*>(&a.storage)->sin_addr.s_addr) >> 24) == 127;
  }
  const auto& v6 = reinterpret_cast<const sockaddr_in6*>(&a.storage)->sin6_addr;
  return IN6_IS_ADDR_LOOPBACK(&v6);
}

// Why `a` cannot be one unicast peer, or nullptr.
const char* not_unicast(const board::SocketAddress& a) {
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

std::uint16_t port_of(const board::SocketAddress& a) {
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
  if (const auto problem = board::interface_name_problem(c.can_interface))
    throw fail(fmt::format("can '{}': not an interface name: {}", cut(c.can_interface), *problem));
  std::string error;
  const auto bind = board::parse_socket_address(c.bind, error);
  if (!bind) throw fail("bind " + cut(error, 200));
  const auto peer = board::parse_socket_address(c.peer, error);
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
