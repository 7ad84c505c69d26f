#pragma once
// Everything that makes a lever an HSI or a TOP, as data. Defaults describe the testbed's levers; the HIL
// and the board runner load their own.
#include <cmath>
#include <cstdint>

#include "lever/codec/config.hpp"
#include "lever/fw/adaptive_window_velocity.hpp"
#include "lever/fw/controllers.hpp"
#include "lever/fw/homing.hpp"
#include "lever/fw/passivity.hpp"
#include "lever/fw/quadrature_decoder.hpp"
#include "lever/fw/step_timing.hpp"
#include "lever/fw/strain_gauge.hpp"
#include "lever/fw/tick.hpp"
#include "lever/fw/velocity_estimator.hpp"
#include "lever/protocol/messages.hpp"

namespace lever::fw {

// The velocity the HSI transmits. The paper (III-E) sends "a discrete time difference approximation of the
// measured quantized position": exactly zero at rest, so at rest its deadband sends nothing. The tracking
// estimate is smoother but never exactly zero. The HSI's own damping uses the estimate either way. A board
// sends the estimate by default: the difference's one-count steps (0.38 rad/s at 16384 counts per turn) reach
// the TOP's damping term and make a stiff contact bounce harder (the HIL's paper scenarios use the difference).
// The adaptive window is a difference too, over the longest window (up to 20 ms) the counts allow: finer steps
// while the lever moves slowly, still exactly zero at rest (adaptive_window_velocity.hpp).
enum class MotionVelocity : std::uint8_t { difference, estimate, adaptive_window };
// In the order the options list them; a board's lever-fw takes difference and estimate (docs/lever-fw.md).
inline constexpr MotionVelocity kAllMotionVelocities[] = {MotionVelocity::difference, MotionVelocity::adaptive_window,
                                                          MotionVelocity::estimate};
constexpr const char* name(MotionVelocity v) noexcept {
  return v == MotionVelocity::difference ? "difference"
         : v == MotionVelocity::estimate ? "estimate"
                                         : "adaptive-window";
}

struct LeverConfig {
  protocol::Role role = protocol::Role::hsi;
  std::uint8_t pair = 0;  // 0..15, selects the CAN ids

  // Link: silence is not loss. The timeout spans four heartbeats, so one late or lost heartbeat never latches
  // COMMS (a timeout equal to the period did, at rest, on the first late one).
  Tick heartbeat_period = 25;  // 40 Hz
  Tick comms_timeout = 100;    // peer silent longer than this latches COMMS
  Tick refresh_period = 100;   // the data sender transmits at least this often, so a lost update heals
  // A frame that brings a stream to rest is sent again this much later (0: never), so a lost one heals in
  // 10 ms rather than a refresh period: one encoder count per tick (0.38 rad/s) held for 10 ms is 3.8 mrad.
  Tick rest_repeat = 10;

  // Deadband per direction (cut-off in Hz). Only the sending end of a direction uses its codec config.
  // The floors are not the paper's rule (floor 0) on purpose: a smooth velocity estimate decays toward zero
  // by more than p every tick and a strain gauge's noise never is zero, so without a floor the pure rule
  // sends nearly every sample at rest (measured: 82 % velocity frames in the closed-loop test).
  codec::Config<double> motion_codec{codec::Mode::deadband, 0.1, 0.02, 0.0};  // HSI velocity, rad/s
  codec::Config<double> force_codec{codec::Mode::deadband, 0.1, 0.05, 0.0};   // TOP contact force, N
  MotionVelocity motion_velocity = MotionVelocity::estimate;

  // Sensors.
  double counts_per_rev = 16384.0;  // 4096 lines read x4
  std::uint8_t counter_bits = 32;   // width of a hardware counter (CountingEncoderPort); edge ports ignore it
  QuadratureDecoder::Config decoder{};
  VelocityEstimator::Config velocity{};
  AdaptiveWindowVelocity::Config adaptive_window{};  // used when motion_velocity is adaptive_window
  StrainGauge::Config gauge{};
  bool use_force_sensor = true;  // TOP: the contact force; HSI: only for closed-loop force display
  Homing::Config homing{};       // method absolute: the encoder needs no homing

  // Timing.
  StepTiming::Config timing{};

  // Control.
  PositionController::Config position{};
  ForceDisplay::Config display{};
  // Passivity under network delay (docs/firmware.md): off by default, as the paper's chain; the port's force
  // arm is display.lever_arm_m on both levers.
  PassivityConfig passivity{};

  // Safety.
  double torque_limit_nm = 1.0;        // never exceeded, whatever arrives on the bus
  Tick torque_saturation_ticks = 250;  // demand above the limit this long is a fault
  double position_min_rad = -1.0;      // checked only while the position is valid
  double position_max_rad = 1.0;
  double safe_hold_torque_nm = 0.3;  // TOP after a fault: hold position with at most this torque...
  Tick safe_hold_ticks = 500;        // ...for this long, then zero torque
};

// Under tdpa the TOP's passivity port limits the velocity the TOP applies and counts its power; the reference's
// low-pass after it would apply a velocity the port never counted, and before it lags the passive reference
// (docs/firmware.md, "Passivity under delay"). The HSI has no position loop: the key does nothing there.
constexpr bool reference_low_pass_conflicts(const LeverConfig& c) noexcept {
  return c.role == protocol::Role::top && c.passivity.mode == PassivityMode::tdpa &&
         c.position.reference_velocity_cutoff_hz > 0.0;
}

constexpr bool is_valid(const LeverConfig& c) noexcept {
  const auto& h = c.homing;
  return c.pair < protocol::kPairCount && c.heartbeat_period > 0 && c.comms_timeout > 0 && c.refresh_period > 0 &&
         codec::runs_at(c.motion_codec, 1.0 / kSecondsPerTick) &&
         codec::runs_at(c.force_codec, 1.0 / kSecondsPerTick) && c.counts_per_rev > 0 && c.counter_bits >= 8 &&
         c.counter_bits <= 32 && c.torque_limit_nm > 0 && c.safe_hold_torque_nm >= 0 &&
         c.safe_hold_torque_nm <= c.torque_limit_nm && c.position_min_rad < c.position_max_rad &&
         c.gauge.stale_after > 0 && c.gauge.tare_samples > 0 && c.timing.overrun_periods >= 1.0 &&
         c.timing.fault_after >= 1 && c.timing.window >= 1 && c.timing.window <= StepTiming::kMaxWindow &&
         c.timing.long_step_us > 0 && (h.direction == 1.0 || h.direction == -1.0) && h.speed_rad_s > 0 &&
         h.torque_limit_nm > 0 && h.torque_limit_nm <= c.torque_limit_nm && h.stall_ticks > 0 &&
         std::isfinite(h.home_position_rad) && h.max_travel_rad > 0 && is_valid(c.passivity) &&
         is_valid(c.adaptive_window) && c.display.lever_arm_m > 0 && !reference_low_pass_conflicts(c);
}

}  // namespace lever::fw
