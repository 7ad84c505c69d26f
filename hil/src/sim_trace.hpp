#pragma once
// lever-hil run's per-tick trace: one TraceRow a scenario tick, to the configured sink as it is made (bounded
// memory) or kept in the result.
#include <functional>
#include <vector>

#include "lever/hil/simulation.hpp"
#include "lever/hil/world.hpp"
#include "sim_levers.hpp"
#include "sim_metrics.hpp"

namespace lever::hil {

class SimTrace {
 public:
  explicit SimTrace(const SimConfig& config) : on_(config.record_trace), sink_(config.trace_sink) {}

  void step(double t, const TickForces& forces, const World& world, const SimLevers& levers) {
    if (!on_) return;
    const auto& hl = *levers.hsi().lever;
    const auto& tl = *levers.top().lever;
    const TraceRow row{t,
                       world.hsi().angle(),
                       world.top().angle(),
                       hl.telemetry().velocity_rad_s,
                       tl.telemetry().position_ref_rad,
                       forces.contact,
                       forces.measured,
                       forces.displayed,
                       levers.hsi().torque(),
                       levers.top().torque(),
                       forces.hand,
                       hl.telemetry().sent_data,
                       tl.telemetry().sent_data,
                       static_cast<int>(hl.supervisor().state()),
                       static_cast<int>(tl.supervisor().state())};
    if (sink_) {
      sink_(row);
    } else {
      rows_.push_back(row);
    }
  }
  void finish(SimResult& result) { result.trace = std::move(rows_); }

 private:
  bool on_;
  const std::function<void(const TraceRow&)>& sink_;
  std::vector<TraceRow> rows_;
};

}  // namespace lever::hil
