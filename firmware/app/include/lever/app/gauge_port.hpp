#pragma once
// The Modbus strain gauge as the core's ForcePort: the poll thread's newest sample, stamped on the firmware's
// clock by its age at this step (the loop sets now_tick and now_ns before each step), so the core judges its
// staleness in ticks. A lever that does not read its gauge has none.
#include <cstdint>
#include <optional>

#include "lever/fw/hal.hpp"
#include "lever/platform/modbus_gauge.hpp"

namespace lever::app {

struct GaugePort {
  const platform::ModbusGauge* gauge = nullptr;
  fw::Tick now_tick = 0;
  std::int64_t now_ns = 0;

  std::optional<fw::ForceReading> latest() const noexcept {
    if (gauge == nullptr) return std::nullopt;
    const auto s = gauge->latest();
    if (!s) return std::nullopt;
    const std::int64_t age_ns = s->monotonic_ns >= now_ns ? 0 : now_ns - s->monotonic_ns;
    const auto age_ticks = static_cast<fw::Tick>(age_ns / 1'000'000);
    return fw::ForceReading{s->newtons, age_ticks >= now_tick ? 0 : now_tick - age_ticks, false, s->saturated};
  }
};
static_assert(fw::ForcePort<GaugePort>);

}  // namespace lever::app
