#pragma once
// Contact force from a weighing amplifier: calibration, tare, staleness and saturation. A sample too old to
// trust yields no value at all (std::nullopt), never the last number silently reused.
#include <cstdint>
#include <optional>

#include "lever/fw/hal.hpp"  // ForceReading
#include "lever/fw/tick.hpp"

namespace lever::fw {

class StrainGauge {
 public:
  struct Config {
    double newton_per_count = 100.0 / 65536.0;  // 16-bit amplifier over +-50 N
    double offset_counts = 0.0;                 // zero-force code, replaced by tare
    double raw_min = -32768.0;                  // readings at or beyond these are saturated
    double raw_max = 32767.0;
    Tick stale_after = 5;             // ticks; an amplifier sampling at 600 Hz delivers every 1.7 ms
    std::uint16_t tare_samples = 64;  // readings averaged by a tare
  };
  struct State {
    std::optional<double> force;  // newtons, calibrated; empty when stale or never read
    bool stale = true;
    bool saturated = false;
    Tick last_tick = 0;
    bool seen = false;
    double value_counts = 0.0;  // newest raw reading
    double offset_counts = 0.0;
    std::uint16_t tare_left = 0;
    double tare_sum = 0.0;
    std::uint32_t tares = 0;  // completed since boot: what a host confirms a tare by (the settings frame)
    // Readings the source marked failed (ForceReading::error: a Modbus timeout, CRC error, exception...),
    // counted once per failure by its tick. They never refresh the force: staleness tells when it is gone.
    std::uint32_t failed_readings = 0;
    Tick failure_tick = 0;
    bool failure_seen = false;
  };

  constexpr StrainGauge() noexcept : StrainGauge(Config{}) {}
  explicit constexpr StrainGauge(const Config& config) noexcept : config_(config) {
    state_.offset_counts = config.offset_counts;
  }
  constexpr const Config& config() const noexcept { return config_; }
  constexpr const State& state() const noexcept { return state_; }

  // The newest reading the HAL has (possibly the same as last tick), evaluated at `now`.
  constexpr std::optional<double> update(const std::optional<ForceReading>& reading, Tick now) noexcept {
    if (reading && !reading->error) {
      const bool fresh = !state_.seen || reading->tick != state_.last_tick;
      state_.seen = true;
      state_.last_tick = reading->tick;
      state_.saturated = reading->saturated || reading->raw <= config_.raw_min || reading->raw >= config_.raw_max;
      if (fresh && state_.tare_left > 0) accumulate_tare(reading->raw);
      state_.value_counts = reading->raw;
    } else if (reading) {
      if (!state_.failure_seen || reading->tick != state_.failure_tick) {
        if (state_.failed_readings != UINT32_MAX) ++state_.failed_readings;
        state_.failure_tick = reading->tick;
        state_.failure_seen = true;
      }
    }
    state_.stale = !state_.seen || now - state_.last_tick > config_.stale_after || state_.last_tick > now;
    if (state_.stale) {
      state_.force.reset();
    } else {
      state_.force = (state_.value_counts - state_.offset_counts) * config_.newton_per_count;
    }
    return state_.force;
  }

  // Average the next tare_samples fresh readings and take them as zero force.
  constexpr void start_tare() noexcept {
    state_.tare_left = config_.tare_samples;
    state_.tare_sum = 0.0;
  }
  constexpr bool taring() const noexcept { return state_.tare_left > 0; }

 private:
  constexpr void accumulate_tare(double raw) noexcept {
    state_.tare_sum += raw;
    if (--state_.tare_left == 0) {
      state_.offset_counts = state_.tare_sum / config_.tare_samples;
      ++state_.tares;
    }
  }

  Config config_;
  State state_;
};

}  // namespace lever::fw
