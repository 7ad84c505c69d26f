#include "fault_injector.hpp"

#include <algorithm>

namespace lever::hil {

bool FaultInjector::step(double t, fw::Tick tick, bool scenario, Transport& transport, SimLevers& levers) {
  clear(transport, levers);
  bool any_active = false;
  for (std::size_t i = 0; scenario && i < faults_.size(); ++i) {
    const auto& f = faults_[i];
    const bool active = t >= f.start_s && t < f.start_s + f.duration_s;
    apply(i, active, t, tick, transport, levers);
    const bool counts = active || (f.kind == FaultKind::reboot && t >= f.start_s && t < f.start_s + 1e-3);
    if (counts && f.kind != FaultKind::delay_step) any_active = true;
    if (counts) quiet_until_ = std::max(quiet_until_, t + rearm_after_s_);
  }
  return any_active || t < quiet_until_;
}

void FaultInjector::clear(Transport& transport, SimLevers& levers) {
  for (NetworkLink* link : {&transport.to_top(), &transport.to_hsi()}) {
    link->set_down(false);
    link->set_burst_loss(0.0);
    link->set_extra_delay_ms(0.0);
  }
  levers.hsi().skip = levers.top().skip = false;
}

void FaultInjector::apply(std::size_t i, bool active, double t, fw::Tick tick, Transport& transport,
                          SimLevers& levers) {
  const auto& f = faults_[i];
  const bool at_hsi = f.site == Site::hsi;
  SimHal& hal = at_hsi ? levers.hsi().hal : levers.top().hal;
  CanBus& bus = at_hsi ? transport.hsi_bus() : transport.top_bus();
  NetworkLink* links[] = {&transport.to_top(), &transport.to_hsi()};
  switch (f.kind) {
    case FaultKind::link_down:
      if (active)
        for (auto* link : links) link->set_down(true);
      break;
    case FaultKind::burst_loss:
      if (active)
        for (auto* link : links) link->set_burst_loss(0.5);
      break;
    case FaultKind::delay_step:
      if (active)
        for (auto* link : links) link->set_extra_delay_ms(f.value);
      break;
    case FaultKind::bus_off:
      bus.set_bus_off(hal.can_.node, active);
      break;
    case FaultKind::encoder_glitch:
      if (active) hal.encoder_.glitch();
      break;
    case FaultKind::gauge_stale:
      hal.gauge_.set_frozen(active);
      break;
    case FaultKind::gauge_saturated:
      hal.gauge_.set_saturated(active);
      break;
    case FaultKind::motor_fault:
      hal.motor_.fault = active;
      break;
    case FaultKind::tick_late:
      if (active) (at_hsi ? levers.hsi().skip : levers.top().skip) = true;
      break;
    case FaultKind::reboot:
      if (!rebooted_[i] && t >= f.start_s) {
        if (active) {
          at_hsi ? levers.hsi().go_down() : levers.top().go_down();
        } else {
          at_hsi ? levers.hsi().boot(tick) : levers.top().boot(tick);
          rebooted_[i] = true;
        }
      }
      break;
  }
}

}  // namespace lever::hil
