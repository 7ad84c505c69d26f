#pragma once
// The testbed of lever-hil run as its parts: the transport, the levers at their sites, the world (mechanics, wall,
// operator), the host console, the injected faults, and what is measured (metrics, fault reactions, trace). One
// step() is one millisecond of all of them, in the order a tick happens on the rig.
#include "fault_injector.hpp"
#include "fault_watch.hpp"
#include "host_console.hpp"
#include "lever/hil/simulation.hpp"
#include "lever/hil/world.hpp"
#include "sim_levers.hpp"
#include "sim_metrics.hpp"
#include "sim_trace.hpp"
#include "transport.hpp"

namespace lever::hil {

class SimRig {
 public:
  explicit SimRig(const SimConfig& config);
  SimRig(const SimRig&) = delete;  // the levers' HALs point into it
  SimRig& operator=(const SimRig&) = delete;

  // Power-up, homing and arming: steps until both levers are armed and returns that tick, the scenario's tick 0.
  fw::Tick power_up();
  // One scenario tick, then what it measured.
  void scenario_step(fw::Tick tick);
  void finish(SimResult& result);

  HostConsole& host() { return host_; }
  Nanos now() const { return now_; }

 private:
  void step(fw::Tick tick, double t);
  void observe(double t, fw::Tick tick) const {
    if (config_.observer) config_.observer(levers_.view(t, tick));
  }

  const SimConfig& config_;
  Nanos now_ = 0;
  fw::Tick start_ = 0;  // the last tick before the scenario; 0 while powering up
  PowerUpAngles angles_;
  Transport transport_;
  SimLevers levers_;
  World world_;
  HostConsole host_;
  FaultInjector faults_;
  SimMetrics metrics_;
  FaultWatch fault_watch_;
  SimTrace trace_;
  TickForces forces_;
};

}  // namespace lever::hil
