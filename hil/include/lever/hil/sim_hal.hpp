#pragma once
// The board as the firmware core sees it, made of models: the HAL of HsiLever<SimHal> and TopLever<SimHal>.
#include <cstdint>

#include "lever/fw/hal.hpp"
#include "lever/hil/can_bus.hpp"
#include "lever/hil/quadrature_encoder.hpp"
#include "lever/hil/strain_gauge_model.hpp"

namespace lever::hil {

inline constexpr Nanos kFirmwareTxDelay = 20'000;  // from step() to the frame in the controller's queue

struct SimMotor {
  fw::MotorCommand last;
  bool fault = false;
  void command(const fw::MotorCommand& c) { last = c; }
  bool driver_fault() const { return fault; }
};

struct SimCan {
  CanBus* bus = nullptr;
  CanBus::Node node = 0;
  const Nanos* now = nullptr;
  Nanos tx_delay = kFirmwareTxDelay;  // 0 when both levers run in one controller: a frame is a memory write
  bool receive(protocol::CanFrame& f) { return bus->receive(node, f); }
  bool send(const protocol::CanFrame& f) { return bus->send(node, f, *now + tx_delay); }
};

struct SimHal {
  SimHal(double counts_per_rev, double angle, const StrainGaugeParams& gauge, std::uint64_t seed)
      : encoder_(counts_per_rev, angle), gauge_(gauge, seed) {}
  QuadratureEncoder encoder_;
  StrainGaugeModel gauge_;
  SimMotor motor_;
  SimCan can_;
  QuadratureEncoder& encoder() { return encoder_; }
  StrainGaugeModel& force() { return gauge_; }
  SimMotor& motor() { return motor_; }
  SimCan& can() { return can_; }
};
static_assert(fw::LeverHal<SimHal>);

}  // namespace lever::hil
