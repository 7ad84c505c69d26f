#include "status_line.hpp"

#include <nlohmann/json.hpp>

namespace lever::view {
namespace {

using nlohmann::json;

std::optional<double> number_at(const json& object, const char* key) {
  const auto it = object.find(key);
  if (it == object.end() || !it->is_number()) return std::nullopt;
  return it->get<double>();
}

std::uint64_t count_at(const json& object, const char* key) {
  const auto it = object.find(key);
  return it != object.end() && it->is_number_unsigned() ? it->get<std::uint64_t>() : 0;
}

StatusLine lever_status(const json& j) {
  LeverStatus s;
  const auto& role = j["role"];
  if (!role.is_string()) return std::monostate{};
  if (role == "hsi") {
    s.role = protocol::Role::hsi;
  } else if (role == "top") {
    s.role = protocol::Role::top;
  } else {
    return std::monostate{};
  }
  const auto pair = j.find("pair");
  if (pair == j.end() || !pair->is_number_unsigned() || pair->get<std::uint64_t>() >= protocol::kPairCount)
    return std::monostate{};
  s.pair = static_cast<std::uint8_t>(pair->get<std::uint64_t>());
  if (const auto it = j.find("state"); it != j.end() && it->is_string()) s.state = it->get<std::string>();
  if (const auto it = j.find("faults"); it != j.end() && it->is_array()) {
    for (const auto& f : *it)
      if (f.is_string()) s.faults.push_back(f.get<std::string>());
  }
  if (const auto it = j.find("position_valid"); it != j.end() && it->is_boolean()) s.position_valid = it->get<bool>();
  s.position_rad = number_at(j, "position_rad");
  s.velocity_rad_s = number_at(j, "velocity_rad_s");
  s.force_n = number_at(j, "force_n");
  s.torque_nm = number_at(j, "torque_nm");
  if (const auto it = j.find("data_sent"); it != j.end() && it->is_number_unsigned())
    s.data_sent = it->get<std::uint64_t>();
  return s;
}

StatusLine bridge_status(const json& j) {
  BridgeStatus s;
  s.bus_load = number_at(j, "bus_load");
  if (const auto it = j.find("to_network"); it != j.end() && it->is_object())
    s.to_network_per_s = number_at(*it, "frames_per_s");
  if (const auto it = j.find("from_network"); it != j.end() && it->is_object()) {
    s.from_network_per_s = number_at(*it, "frames_per_s");
    s.sequence_gaps = count_at(*it, "sequence_gaps");
    s.reordered = count_at(*it, "reordered");
  }
  if (const auto it = j.find("latency_us"); it != j.end() && it->is_object()) s.latency_p99_us = number_at(*it, "p99");
  if (const auto it = j.find("can"); it != j.end() && it->is_string()) s.can = it->get<std::string>();
  return s;
}

}  // namespace

StatusLine parse_status_line(std::string_view line) {
  const json j = json::parse(line, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return std::monostate{};
  if (j.contains("role")) return lever_status(j);
  if (j.contains("to_network")) return bridge_status(j);
  return std::monostate{};
}

}  // namespace lever::view
