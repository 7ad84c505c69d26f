#pragma once
// The sphere-3dof's two clocks (docs/hil-model.md, "The teleoperator's own clock"): the OP ticks at k ms, the
// simulation's own time; the TOP at phase + j ms (1 + drift), both drawn per seed. It also answers which tick of one
// side the undistorted system's sample, sent at the link's nominal worst delay, reaches on the other: the metrics'
// reference.
#include <cstdint>
#include <optional>

#include "lever/hil/can_bus.hpp"
#include "lever/hil/sphere3dof.hpp"
#include "sphere_packets.hpp"

namespace lever::hil {

class SphereClocks {
 public:
  // With top_clock op_playout the TOP's tick j is the OP's tick j, and the undistorted system's delays are the
  // play-out's whole ticks.
  SphereClocks(const SphereConfig& c, const SphereDelays& delays);

  // The TOP's tick j on the OP's clock (ns), j = 0, 1, ...
  Nanos top_tick_ns(std::uint64_t j) const;
  // The TOP's own reading of a time on the OP's clock, in seconds (its tick j reads j ms exactly).
  double top_clock_at(Nanos op_ns) const;
  // The newest TOP tick whose packet, sent at the tick and delayed by the nominal worst delay, has reached the OP by
  // its tick k; none before the first.
  std::optional<std::uint64_t> top_tick_heard_by_op(std::uint64_t k) const;
  // The newest OP tick (k >= 1) whose sample, delayed likewise, has reached the TOP by its tick j.
  std::optional<std::uint64_t> op_tick_heard_by_top(std::uint64_t j) const;

  double phase_ms() const { return static_cast<double>(phase_ns_) * 1e-6; }
  double drift_ppm() const { return drift_ * 1e6; }

 private:
  bool own_;
  SphereDelays delays_;
  Nanos phase_ns_ = 0;
  double drift_ = 0.0;
  double period_ns_ = 1e6;
  Nanos worst_delay_ns_ = 0;
};

}  // namespace lever::hil
