#pragma once
// The physical world lever-hil serve plays on the wall clock: lever-hil run's World (the levers' mechanics, the
// wall, the operator) and the strain gauges' amplifiers, stepped through the devices each lever-fw reads and
// writes: the motors read back, the encoders' lines set, the gauges' registers filled.
#include "lever/hil/simulation.hpp"
#include "lever/hil/strain_gauge_model.hpp"
#include "lever/hil/world.hpp"
#include "serve_devices.hpp"
#include "serve_probe.hpp"

namespace lever::hil {

// What one tick of the world gave.
struct ServeTick {
  fw::MotorCommand hsi_command, top_command;  // the motors as read back
  double contact = 0.0;                       // N: the wall on the TOP's tip
  double hand = 0.0;                          // N: the hand on the HSI's handle
  double measured = 0.0;                      // N: the TOP's amplifier's newest reading, before the register layout
};

class ServeWorld {
 public:
  ServeWorld(const SimConfig& sim, std::uint64_t seed);

  double hsi_angle() const { return world_.hsi().angle(); }
  double top_angle() const { return world_.top().angle(); }
  const World& world() const { return world_; }
  void start_operator(fw::Tick tick) { world_.start_operator(tick); }
  // The gauges' noise from here on is the seed's, however many ticks came before (homing and arming take as
  // long as the levers' programs and their commands take).
  void reseed_noise(std::uint64_t seed);

  // One millisecond under the motors as the levers' programs now drive them.
  ServeTick step(fw::Tick tick, bool hand_on, LeverDevices& hsi, LeverDevices& top, ServeProbe* probe);

 private:
  void sense(ServeTick& s, fw::Tick tick, LeverDevices& hsi, LeverDevices& top, ServeProbe* probe);

  double step_n_;
  World world_;
  StrainGaugeModel top_gauge_, hsi_gauge_;
  double measured_ = 0.0;
};

}  // namespace lever::hil
