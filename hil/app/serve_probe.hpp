#pragma once
// A per-tick observer of lever-hil serve's loop (a latency probe, a logger): it is called at the two moments the
// world touches the levers' devices and at the end of each tick, on the loop's thread, and must not block. Every
// hook does nothing by default; override the ones needed and pass the probe to run_serve.
#include <chrono>
#include <cstdint>

#include "lever/fw/hal.hpp"
#include "lever/hil/devices/motor_readback.hpp"

namespace lever::hil {

class ServeProbe {
 public:
  using Clock = std::chrono::steady_clock;
  virtual ~ServeProbe() = default;

  // The motors were just read back (the duty and lines each lever-fw wrote), before the world moves under them.
  virtual void motors_read(fw::Tick, const devices::MotorReading& /*hsi*/, const devices::MotorReading& /*top*/) {}
  // The encoders' lines were just given the counts of the world's new angles; their threads write the edges.
  virtual void encoders_set(fw::Tick, std::int64_t /*hsi_count*/, std::int64_t /*top_count*/) {}
  // The tick is over; `scenario` is false before both levers were armed.
  virtual void tick_done(fw::Tick, bool /*scenario*/) {}
};

}  // namespace lever::hil
