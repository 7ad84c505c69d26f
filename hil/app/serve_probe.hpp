#pragma once
// A per-tick observer of lever-hil serve's loop (a latency probe, a logger): it is called at the moments the world
// touches the levers' devices and at the end of each tick, on the loop's thread, and must not block. It may add a
// stimulus to what the world puts on the sensors. Every hook does nothing by default; override the ones needed and
// pass the probe to run_serve.
#include <chrono>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>

#include "lever/app/fw_config.hpp"
#include "lever/fw/hal.hpp"
#include "lever/hil/devices/motor_readback.hpp"
#include "serve_devices.hpp"

namespace lever::hil {

class ServeProbe {
 public:
  using Clock = std::chrono::steady_clock;
  virtual ~ServeProbe() = default;

  // Once, when the levers' devices are open; false stops serve (the probe said why on stderr).
  virtual bool attach(const app::FwConfig& /*hsi*/, const app::FwConfig& /*top*/, const LeverDevices& /*hsi*/,
                      const LeverDevices& /*top*/) {
    return true;
  }
  // True: the world holds both levers still (as clamped on a bench) instead of moving them under their motors.
  virtual bool holds_levers() const { return false; }
  // Added to the count the world drives the HSI's encoder to.
  virtual std::int64_t hsi_count_offset() const { return 0; }
  // When set, what the TOP's gauge reads instead of the world's amplifier (a signal generator on its input).
  virtual std::optional<double> top_force_n() const { return std::nullopt; }

  // The motors were just read back (the duty and lines each lever-fw wrote), before the world moves under them.
  virtual void motors_read(fw::Tick, const devices::MotorReading& /*hsi*/, const devices::MotorReading& /*top*/) {}
  // The encoders' lines were just given the counts of the world's new angles; their threads write the edges.
  virtual void encoders_set(fw::Tick, std::int64_t /*hsi_count*/, std::int64_t /*top_count*/) {}
  // The TOP's gauge registers were just given a force; `replies_before` answers had been sent before it.
  virtual void top_gauge_set(fw::Tick, std::uint64_t /*replies_before*/) {}
  // The tick is over; `scenario` is false before both levers were armed.
  virtual void tick_done(fw::Tick, bool /*scenario*/) {}
  // What it measured, into serve's JSON report.
  virtual void report(nlohmann::json& /*report*/) const {}
};

}  // namespace lever::hil
