#pragma once
// The Modbus strain gauge as the core's ForcePort: the poll thread's newest sample, stamped on the firmware's
// clock by its age at this step (the loop sets now_tick and now_ns before each step), so the core judges its
// staleness in ticks. A lever that does not read its gauge has none.
#include <cstdint>
#include <optional>

#include "lever/board/modbus_gauge.hpp"
#include "lever/fw/hal.hpp"

namespace lever::app {

struct GaugePort {
  explicit GaugePort(const board::ModbusGauge* g = nullptr) noexcept : gauge(g) {}

  const board::ModbusGauge* gauge = nullptr;
  fw::Tick now_tick = 0;
  std::int64_t now_ns = 0;

  // The newest good sample; or, when the newest poll failed (a timeout, a CRC error, an exception, a lost
  // connection), that failure as a reading with `error` set, stamped when it happened: the core counts it and
  // keeps the last good value aging. Each sample and each failure is stamped once, when first seen, so that
  // its tick does not move by the rounding of later steps (the core tells a new reading by its tick).
  std::optional<fw::ForceReading> latest() noexcept {
    if (gauge == nullptr) return std::nullopt;
    const auto s = gauge->latest();
    const std::int64_t failed_ns = gauge->newest_failure_ns();
    if (failed_ns != 0 && (!s || failed_ns > s->monotonic_ns)) {
      if (failed_ns != failure_ns_) {
        failure_ns_ = failed_ns;
        failure_tick_ = tick_at(failed_ns);
      }
      return fw::ForceReading{s ? s->newtons : 0.0, failure_tick_, true, false};
    }
    if (!s) return std::nullopt;
    if (s->sequence != sample_sequence_) {
      sample_sequence_ = s->sequence;
      sample_tick_ = tick_at(s->monotonic_ns);
    }
    return fw::ForceReading{s->newtons, sample_tick_, false, s->saturated};
  }

  // The firmware tick at which `ns` (CLOCK_MONOTONIC) was, by its age at this step.
  fw::Tick tick_at(std::int64_t ns) const noexcept {
    const std::int64_t age_ns = ns >= now_ns ? 0 : now_ns - ns;
    const auto age_ticks = static_cast<fw::Tick>(age_ns / 1'000'000);
    return age_ticks >= now_tick ? 0 : now_tick - age_ticks;
  }

 private:
  std::uint64_t sample_sequence_ = 0;  // samples count from 1
  fw::Tick sample_tick_ = 0;
  std::int64_t failure_ns_ = 0;
  fw::Tick failure_tick_ = 0;
};
static_assert(fw::ForcePort<GaugePort>);

}  // namespace lever::app
