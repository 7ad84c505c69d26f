#include "lever/board/modbus_gauge_config.hpp"

#include <arpa/inet.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

namespace lever::board {
namespace {

// The rates every Linux UART driver and libmodbus name; an amplifier offering another one is mis-typed.
constexpr std::array kStandardBauds{1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200, 230400, 460800, 921600};

std::string real(double value) {
  std::array<char, 32> buffer{};
  std::snprintf(buffer.data(), buffer.size(), "%g", value);
  return buffer.data();
}

bool is_numeric_address(const std::string& host) {
  std::array<unsigned char, sizeof(in6_addr)> scratch{};
  return ::inet_pton(AF_INET, host.c_str(), scratch.data()) == 1 ||
         ::inet_pton(AF_INET6, host.c_str(), scratch.data()) == 1;
}

std::optional<std::string> check(const ModbusTcpEndpoint& tcp) {
  if (!is_numeric_address(tcp.host)) {
    return "tcp.host: \"" + tcp.host + "\" is not a numeric IPv4 or IPv6 address (names are not resolved)";
  }
  if (tcp.port < 1 || tcp.port > 65535) return "tcp.port: " + std::to_string(tcp.port) + " is outside 1..65535";
  if (!((tcp.unit_id >= 0 && tcp.unit_id <= 247) || tcp.unit_id == 255)) {
    return "tcp.unit_id: " + std::to_string(tcp.unit_id) + " is outside 0..247 and not 255";
  }
  return std::nullopt;
}

std::optional<std::string> check(const ModbusRtuEndpoint& rtu) {
  if (rtu.device.empty()) return "rtu.device: empty";
  if (std::find(kStandardBauds.begin(), kStandardBauds.end(), rtu.baud) == kStandardBauds.end()) {
    return "rtu.baud: " + std::to_string(rtu.baud) + " is not a standard rate (1200, 2400, ... 115200, ... 921600)";
  }
  if (rtu.parity != Parity::none && rtu.parity != Parity::even && rtu.parity != Parity::odd) {
    return "rtu.parity: must be N, E or O";
  }
  if (rtu.data_bits != 8) return "rtu.data_bits: " + std::to_string(rtu.data_bits) + " is not 8 (RTU frames are bytes)";
  if (rtu.stop_bits != 1 && rtu.stop_bits != 2)
    return "rtu.stop_bits: " + std::to_string(rtu.stop_bits) + " is not 1 or 2";
  if (rtu.slave_id < 1 || rtu.slave_id > 247) {
    return "rtu.slave_id: " + std::to_string(rtu.slave_id) + " is outside 1..247 (0 is broadcast, never answered)";
  }
  return std::nullopt;
}

// "FIELD: must be a, b or c" unless `value` is one of `all` (a value cast from a number may be none).
template <typename E, std::size_t N>
std::optional<std::string> one_of(const char* field, E value, const E (&all)[N]) {
  if (std::find(std::begin(all), std::end(all), value) != std::end(all)) return std::nullopt;
  std::string names;
  for (std::size_t i = 0; i < N; ++i) names += (i == 0 ? "" : i + 1 == N ? " or " : ", ") + std::string(name(all[i]));
  return std::string(field) + ": must be " + names;
}

std::optional<std::string> check(const GaugeRegisterMap& map) {
  if (auto e = one_of("registers.function", map.function, kAllRegisterFunctions)) return e;
  if (auto e = one_of("registers.type", map.type, kAllRegisterTypes)) return e;
  if (auto e = one_of("registers.word_order", map.word_order, kAllWordOrders)) return e;
  const int last_address = 65535 - (register_count(map.type) - 1);
  if (map.address < 0 || map.address > last_address) {
    return "registers.address: " + std::to_string(map.address) + " is outside 0.." + std::to_string(last_address) +
           " for this type";
  }
  if (!std::isfinite(map.scale) || map.scale == 0.0) {
    return "registers.scale: " + real(map.scale) + " must be finite and non-zero";
  }
  if (!std::isfinite(map.offset)) return "registers.offset: " + real(map.offset) + " must be finite";
  if (map.saturation_raw_min && std::isnan(*map.saturation_raw_min)) return "registers.saturation_raw_min: NaN";
  if (map.saturation_raw_max && std::isnan(*map.saturation_raw_max)) return "registers.saturation_raw_max: NaN";
  // A bound the register cannot reach would never flag anything: the ±1e15 that once stood in the examples.
  if (map.saturation_raw_min && *map.saturation_raw_min < lowest_value(map.type)) {
    return "registers.saturation_raw_min: " + real(*map.saturation_raw_min) + " is below the lowest value of " +
           "the register type (" + real(lowest_value(map.type)) + "): saturation would never be seen";
  }
  if (map.saturation_raw_max && *map.saturation_raw_max > highest_value(map.type)) {
    return "registers.saturation_raw_max: " + real(*map.saturation_raw_max) + " is above the highest value of " +
           "the register type (" + real(highest_value(map.type)) + "): saturation would never be seen";
  }
  if (map.saturation_raw_min && map.saturation_raw_max && *map.saturation_raw_min >= *map.saturation_raw_max) {
    return "registers.saturation_raw_min: " + real(*map.saturation_raw_min) + " is not below saturation_raw_max " +
           real(*map.saturation_raw_max);
  }
  return std::nullopt;
}

std::optional<std::string> check_timing(const ModbusGaugeConfig& config) {
  using std::chrono::microseconds;
  using std::chrono::milliseconds;
  using std::chrono::seconds;
  if (config.poll_period < microseconds(100) || config.poll_period > seconds(10)) {
    return "poll_period: " + std::to_string(config.poll_period.count()) + " us is outside 100 us..10 s";
  }
  if (config.response_timeout < milliseconds(1) || config.response_timeout > seconds(1)) {
    return "response_timeout: " + std::to_string(config.response_timeout.count()) + " us is outside 1 ms..1 s";
  }
  if (config.reconnect_backoff_max < milliseconds(1) || config.reconnect_backoff_max > seconds(60)) {
    return "reconnect_backoff_max: " + std::to_string(config.reconnect_backoff_max.count()) +
           " ms is outside 1 ms..60 s";
  }
  if (config.reconnect_backoff_initial < milliseconds(1) ||
      config.reconnect_backoff_initial > config.reconnect_backoff_max) {
    return "reconnect_backoff_initial: " + std::to_string(config.reconnect_backoff_initial.count()) +
           " ms is outside 1 ms..reconnect_backoff_max";
  }
  return std::nullopt;
}

}  // namespace

double lowest_value(RegisterType type) noexcept {
  switch (type) {
    case RegisterType::int16:
      return -32768.0;
    case RegisterType::int32:
      return -2147483648.0;
    case RegisterType::float32:
      return -3.4028234663852886e38;
    case RegisterType::uint16:
    case RegisterType::uint32:
      break;
  }
  return 0.0;
}

double highest_value(RegisterType type) noexcept {
  switch (type) {
    case RegisterType::int16:
      return 32767.0;
    case RegisterType::uint16:
      return 65535.0;
    case RegisterType::int32:
      return 2147483647.0;
    case RegisterType::uint32:
      return 4294967295.0;
    case RegisterType::float32:
      break;
  }
  return 3.4028234663852886e38;
}

std::chrono::microseconds longest_gap(const ModbusGaugeConfig& config, int missed_polls) {
  const bool rtu = std::holds_alternative<ModbusRtuEndpoint>(config.transport);
  const std::chrono::microseconds reconnect =
      rtu ? std::chrono::microseconds(config.reconnect_backoff_initial) : config.response_timeout;
  return config.poll_period + (missed_polls + 1) * config.response_timeout + missed_polls * reconnect;
}

int register_count(RegisterType type) noexcept {
  return type == RegisterType::int16 || type == RegisterType::uint16 ? 1 : 2;
}

std::optional<std::string> validate(const ModbusGaugeConfig& config) {
  if (auto problem = std::visit([](const auto& endpoint) { return check(endpoint); }, config.transport)) {
    return problem;
  }
  if (auto problem = check(config.registers)) return problem;
  return check_timing(config);
}

}  // namespace lever::board
