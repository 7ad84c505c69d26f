#pragma once
// lever-hil run's injected faults (--fault): each put in force on the link, a bus, a lever's hardware or its
// firmware while its span lasts, and how long the host waits before it re-arms.
#include <vector>

#include "lever/hil/fault_spec.hpp"
#include "sim_levers.hpp"
#include "transport.hpp"

namespace lever::hil {

class FaultInjector {
 public:
  FaultInjector(const std::vector<FaultSpec>& faults, double rearm_after_s)
      : faults_(faults), rearm_after_s_(rearm_after_s), rebooted_(faults.size(), false) {}

  // The faults in force during the tick at scenario time `t` (none before the scenario). Returns whether they hold
  // the host back: a fault in force, or one that ended less than rearm_after_s ago.
  bool step(double t, fw::Tick tick, bool scenario, Transport& transport, SimLevers& levers);

 private:
  void clear(Transport& transport, SimLevers& levers);
  void apply(std::size_t i, bool active, double t, fw::Tick tick, Transport& transport, SimLevers& levers);

  const std::vector<FaultSpec>& faults_;
  double rearm_after_s_;
  std::vector<bool> rebooted_;
  double quiet_until_ = 0.0;
};

}  // namespace lever::hil
