#pragma once
// Every register type in both word orders, with two values each, and the check that a gauge reads the first
// and then follows the server to the second. Shared by the TCP and RTU tests.
#include <time.h>

#include <array>
#include <catch2/catch.hpp>
#include <vector>

#include "gauge_test_support.hpp"
#include "modbus_test_servers.hpp"

namespace lever::test {

struct TypeCase {
  board::RegisterType type;
  board::WordOrder order;
  double first;
  double second;
};

// Values whose two words differ, so a swapped word order reads something else; negative ones for signed types.
inline const std::array<TypeCase, 8> kTypeCases{{
    {board::RegisterType::int16, board::WordOrder::high_first, 1234, -1234},
    {board::RegisterType::uint16, board::WordOrder::high_first, 54321, 7},
    {board::RegisterType::int32, board::WordOrder::high_first, -123456789, 74565},
    {board::RegisterType::int32, board::WordOrder::low_first, -123456789, 74565},
    {board::RegisterType::uint32, board::WordOrder::high_first, 4000000000.0, 74565},
    {board::RegisterType::uint32, board::WordOrder::low_first, 4000000000.0, 74565},
    {board::RegisterType::float32, board::WordOrder::high_first, static_cast<double>(3.14159274f), -12.5},
    {board::RegisterType::float32, board::WordOrder::low_first, static_cast<double>(3.14159274f), -12.5},
}};

inline std::int64_t monotonic_now_ns() {
  timespec now{};
  ::clock_gettime(CLOCK_MONOTONIC, &now);
  return std::int64_t{now.tv_sec} * 1'000'000'000 + now.tv_nsec;
}

// The server holds `first` in the registers of `function` (and something else in the other table); the gauge
// must read it, scaled, with a CLOCK_MONOTONIC stamp; then the server changes to `second` and the gauge follows.
inline void check_reads_and_follows(ModbusTestServer& server, const board::ModbusTransport& transport,
                                    const TypeCase& type_case, board::RegisterFunction function) {
  using board::RegisterFunction;
  constexpr int kAddress = 3;
  constexpr double kScale = 0.5;
  constexpr double kOffset = -2.0;
  const std::vector<std::uint16_t> decoy{0x1111, 0x1111};
  auto hold = [&](double value) {
    const auto words = registers_for(value, type_case.type, type_case.order);
    server.set_holding(kAddress, function == RegisterFunction::holding ? words : decoy);
    server.set_input(kAddress, function == RegisterFunction::input ? words : decoy);
  };
  hold(type_case.first);

  board::GaugeRegisterMap map;
  map.function = function;
  map.address = kAddress;
  map.type = type_case.type;
  map.word_order = type_case.order;
  map.scale = kScale;
  map.offset = kOffset;
  auto opened = board::ModbusGauge::open(test_config(transport, map));
  REQUIRE(opened.ok());
  const board::ModbusGauge& gauge = opened.value();

  auto holds = [&](double raw) {
    return [&gauge, raw] {
      const auto sample = gauge.latest();
      return sample && sample->raw == raw;
    };
  };
  REQUIRE(eventually(holds(type_case.first)));
  const auto first = *gauge.latest();
  CHECK(first.newtons == type_case.first * kScale + kOffset);
  CHECK_FALSE(first.saturated);
  CHECK(first.monotonic_ns <= monotonic_now_ns());
  CHECK(first.monotonic_ns > monotonic_now_ns() - 1'000'000'000);

  hold(type_case.second);
  REQUIRE(eventually(holds(type_case.second)));
  const auto second = *gauge.latest();
  CHECK(second.newtons == type_case.second * kScale + kOffset);
  CHECK(second.sequence > first.sequence);
  CHECK(second.monotonic_ns > first.monotonic_ns);
  const auto counters = gauge.counters();
  CHECK(counters.errors == 0);
  CHECK(counters.connected);
}

}  // namespace lever::test
