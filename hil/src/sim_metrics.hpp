#pragma once
// What lever-hil run measures on every scenario tick beyond what lever-hil serve can (RunMetrics): the displayed
// force's distortion by cause, seen inside the TOP's sender; the levers' own protection tripping; their
// controllers' dissipated and observed energy; and at the end the firmware's own counters.
#include <cstdint>
#include <optional>
#include <vector>

#include "lever/hil/run_metrics.hpp"
#include "lever/hil/simulation.hpp"
#include "lever/hil/world.hpp"
#include "sim_levers.hpp"

namespace lever::hil {

// The forces of one scenario tick, as the trace and the metrics read them.
struct TickForces {
  double contact = 0.0;    // the wall on the TOP's tip
  double hand = 0.0;       // the hand on the HSI's handle
  double measured = 0.0;   // the TOP's gauge reading (0 while it has none)
  double displayed = 0.0;  // what the HSI displays of the TOP's force (0 while it has none)
};

class SimMetrics {
 public:
  explicit SimMetrics(const SimConfig& config);

  void step(fw::Tick tick, const TickForces& forces, const World& world, const SimLevers& levers);
  void finish(SimResult& result, const SimLevers& levers) const;

 private:
  // A lever's dissipated energy over the run, from its passivity port's count since it last armed.
  struct RunningTotal {
    double last_j = 0.0;
    double total_j = 0.0;
    void add(double since_armed_j) {
      total_j += since_armed_j >= last_j ? since_armed_j - last_j : since_armed_j;  // below the last: it re-armed
      last_j = since_armed_j;
    }
  };
  void count_lever_faults(const SimLevers& levers);
  void add_armed(fw::Tick tick, const TickForces& forces, const World& world, const SimLevers& levers);

  RunMetrics metrics_;
  int nominal_delay_ticks_;
  double prefilter_delay_ms_;
  // The TOP's measurements of the last nominal delay's ticks, for the distortion without the transport delay.
  std::vector<std::optional<double>> measured_history_;
  RunningTotal dissipated_[2];        // HSI, TOP
  bool was_armed_[2] = {true, true};  // the scenario starts with both armed
  SimResult::LeverFaults lever_faults_[2];
  std::uint64_t refresh_frames_ = 0;
  std::uint64_t by_cause_[2][3] = {};          // [HSI velocity, TOP force][fw::SendCause]
  std::uint64_t deadband_in_contact_[2] = {};  // the deadband's, while the TOP touches the wall
  double jnd_, jnd_absolute_n_;
  double hand_sq_ = 0.0;
  std::uint64_t hand_violations_ = 0;
  double min_observed_energy_j_[2] = {0.0, 0.0};
};

}  // namespace lever::hil
