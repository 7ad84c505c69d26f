#pragma once
// lever-hil run's testbed one millisecond at a time, with a program at the host console on the HSI's bus: it sends
// command frames and reads every frame of the bus as a process on the pair's CAN interface would (lever-hil study
// runs the paper's user study this way). Time is the simulation's: the same configuration and the same frames sent
// at the same ticks give the same frames back, bit for bit.
#include <cstdint>
#include <memory>

#include "lever/hil/can_bus.hpp"
#include "lever/hil/simulation.hpp"
#include "lever/protocol/can_frame.hpp"

namespace lever::hil {

class SimRig;

class HostedRig {
 public:
  // The configuration is copied; its duration is not used (the program steps as long as it needs).
  explicit HostedRig(const SimConfig& config);
  ~HostedRig();
  HostedRig(const HostedRig&) = delete;
  HostedRig& operator=(const HostedRig&) = delete;

  // Power-up, homing and arming as in run_simulation; afterwards the scenario runs (the operator at the HSI).
  // Throws std::runtime_error when the levers do not arm within 30 s.
  void power_up();
  // One scenario tick; power_up() comes first (the scenario starts once both levers are armed).
  void step();
  // A frame from the console's node, ready at the current time; false when its transmit queue is full.
  bool send(const protocol::CanFrame& frame);
  // The oldest frame the console's node has received, with the time its last bit was on the wire.
  bool receive(TimedFrame& frame);
  // The simulation's clock: from power-up, on every bus of the run.
  Nanos now() const;
  const SimConfig& config() const { return config_; }

 private:
  SimConfig config_;  // first: the rig holds a reference to it
  std::unique_ptr<SimRig> rig_;
  fw::Tick tick_ = 0;
};

}  // namespace lever::hil
