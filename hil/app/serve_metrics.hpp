#pragma once
// What lever-hil serve measures on every scenario tick: lever-hil run's RunMetrics where both levers are armed,
// and what only serve has (the largest errors, the HSI's motor in contact, the levers' silences).
#include <cstdint>

#include "lever/hil/run_metrics.hpp"
#include "lever/hil/simulation.hpp"
#include "lever/hil/world.hpp"
#include "serve_world.hpp"

namespace lever::hil {

// The levers as their heartbeats on the buses tell.
struct PairHeard {
  bool hsi = false, top = false;  // heard within the window
  bool both_armed = false;
  bool hsi_homing = false;
};

struct ServeExtras {
  double max_position_error_rad = 0.0;
  double hsi_torque_in_contact_sum = 0.0;  // N m, HSI motor torque while the TOP touches the wall
  double max_displayed_force_n = 0.0;
  std::uint64_t hsi_silent_ms = 0, top_silent_ms = 0;  // after the start: no heartbeat within the window
};

class ServeMetrics {
 public:
  explicit ServeMetrics(const SimConfig& sim) : metrics_(sim.jnd, sim.jnd_absolute_n) {}

  // `displayed`: the newest force on the HSI's bus; the frames: the data frames each lever sent in the tick.
  void step(const PairHeard& heard, const ServeTick& s, const World& world, std::uint64_t motion_sent,
            std::uint64_t force_sent, double displayed);
  void finish(SimResult& result) const { metrics_.finish(result); }

  const RunMetrics& run() const { return metrics_; }
  const ServeExtras& extras() const { return extras_; }
  double mean_hsi_torque_in_contact_nm() const {
    return metrics_.contact_ticks() > 0
               ? extras_.hsi_torque_in_contact_sum / static_cast<double>(metrics_.contact_ticks())
               : 0.0;
  }

 private:
  RunMetrics metrics_;
  ServeExtras extras_;
};

}  // namespace lever::hil
