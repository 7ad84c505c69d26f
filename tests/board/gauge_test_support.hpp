#pragma once
// Small helpers the gauge tests share: waiting for a condition with a deadline, registers for a value, a
// config with timeouts short enough for tests.
#include <bit>
#include <chrono>
#include <cstdint>
#include <thread>
#include <vector>

#include "lever/board/modbus_gauge.hpp"

namespace lever::test {

// Polls `condition` every millisecond until it holds or `limit` passes; says which.
template <typename Condition>
bool eventually(Condition condition, std::chrono::milliseconds limit = std::chrono::milliseconds(3000)) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (!condition()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

// The registers an amplifier would hold for `value`: the inverse of the decoder, written separately.
inline std::vector<std::uint16_t> registers_for(double value, board::RegisterType type, board::WordOrder order) {
  using board::RegisterType;
  std::uint32_t bits = 0;
  switch (type) {
    case RegisterType::int16:
      return {static_cast<std::uint16_t>(static_cast<std::int16_t>(value))};
    case RegisterType::uint16:
      return {static_cast<std::uint16_t>(value)};
    case RegisterType::int32:
      bits = static_cast<std::uint32_t>(static_cast<std::int32_t>(value));
      break;
    case RegisterType::uint32:
      bits = static_cast<std::uint32_t>(value);
      break;
    case RegisterType::float32:
      bits = std::bit_cast<std::uint32_t>(static_cast<float>(value));
      break;
  }
  const auto high = static_cast<std::uint16_t>(bits >> 16);
  const auto low = static_cast<std::uint16_t>(bits & 0xFFFF);
  if (order == board::WordOrder::high_first) return {high, low};
  return {low, high};
}

// Defaults but for the waits. The response timeout is the longest allowed, so only a test that silences its
// server sees a timeout (and sets a shorter one), even on a loaded machine: a pty's bytes are handed over by a
// kernel worker thread, which CPU hogs can hold up for tens of milliseconds. The backoff is cut so a test
// that sees a few reconnects stays short.
inline board::ModbusGaugeConfig test_config(board::ModbusTransport transport, board::GaugeRegisterMap registers = {}) {
  board::ModbusGaugeConfig config;
  config.transport = std::move(transport);
  config.registers = registers;
  config.response_timeout = std::chrono::seconds(1);
  config.reconnect_backoff_initial = std::chrono::milliseconds(10);
  config.reconnect_backoff_max = std::chrono::milliseconds(100);
  return config;
}

// The newest sample's sequence number, 0 before the first.
inline std::uint64_t sequence_of(const board::ModbusGauge& gauge) {
  const auto sample = gauge.latest();
  return sample ? sample->sequence : 0;
}

}  // namespace lever::test
