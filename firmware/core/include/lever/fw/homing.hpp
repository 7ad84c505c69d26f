#pragma once
// Finding the lever's reference after power-up (moteus and ODrive keep the same "homed / position valid"
// state). Two routines, chosen by configuration: drive slowly under a small torque limit into a hard stop
// and take the stall as the reference, or drive until the encoder's index line fires. A lever with an
// absolute encoder declares it and needs neither.
#include <cstdint>
#include <optional>

#include "lever/fw/tick.hpp"

namespace lever::fw {

enum class HomingMethod : std::uint8_t { absolute = 0, hard_stop = 1, index = 2 };

class Homing {
 public:
  struct Config {
    HomingMethod method = HomingMethod::hard_stop;
    double direction = -1.0;           // +1 or -1: where the stop (or the index) is from any start
    double speed_rad_s = 0.5;          // slow enough that hitting the stop is gentle
    double kp_nms = 0.05;              // velocity loop: N m per rad/s of speed error...
    double ki_nm = 1.0;                // ...plus N m per rad of accumulated error, which overcomes friction
    double torque_limit_nm = 0.2;      // never more while homing: what presses the stop, or a hand in the way
    double stall_speed_rad_s = 0.05;   // below this, with the torque at its limit...
    Tick stall_ticks = 100;            // ...this long, the lever is at the stop
    double home_position_rad = -0.61;  // lever coordinate of the stop as pressed at torque_limit_nm (or of the index)
    double max_travel_rad = 6.3;       // no stop or index within a turn: give up
    Tick timeout_ticks = 15000;
  };
  enum class Status : std::uint8_t { running, done, failed };
  struct Output {
    double torque_nm = 0.0;
    Status status = Status::running;
  };

  constexpr Homing() noexcept : Homing(Config{}) {}
  explicit constexpr Homing(const Config& config) noexcept : config_(config) {}
  constexpr const Config& config() const noexcept { return config_; }
  constexpr bool needed() const noexcept { return config_.method != HomingMethod::absolute; }

  constexpr void start(Tick now, double raw_angle) noexcept {
    started_ = now;
    start_angle_ = raw_angle;
    integral_ = 0.0;
    stalled_for_ = 0;
  }

  // One tick of the routine. raw_angle and velocity are the encoder's, unreferenced; index_raw_angle is the
  // raw angle at an index edge seen this tick. On done, reference_raw_angle() is where home_position_rad is.
  constexpr Output update(Tick now, double raw_angle, double velocity, std::optional<double> index_raw_angle,
                          double dt) noexcept {
    const double travelled = (raw_angle - start_angle_) * config_.direction;
    if (now - started_ > config_.timeout_ticks || travelled > config_.max_travel_rad || travelled < -0.5)
      return {0.0, Status::failed};  // stuck, running away, or pushed back the other way by more than a bit

    if (config_.method == HomingMethod::index && index_raw_angle) {
      reference_ = *index_raw_angle;
      return {0.0, Status::done};
    }

    const double error = config_.direction * config_.speed_rad_s - velocity;
    const double limit = config_.torque_limit_nm;
    integral_ += config_.ki_nm * error * dt;
    if (integral_ > limit) integral_ = limit;
    if (integral_ < -limit) integral_ = -limit;
    double torque = config_.kp_nms * error + integral_;
    const bool at_limit = torque >= limit || torque <= -limit;
    if (torque > limit) torque = limit;
    if (torque < -limit) torque = -limit;

    const bool slow = velocity < config_.stall_speed_rad_s && velocity > -config_.stall_speed_rad_s;
    stalled_for_ = at_limit && slow ? stalled_for_ + 1 : 0;
    if (stalled_for_ >= config_.stall_ticks) {
      if (config_.method == HomingMethod::index) return {0.0, Status::failed};  // a stop before any index
      reference_ = raw_angle;
      return {0.0, Status::done};
    }
    return {torque, Status::running};
  }

  constexpr double reference_raw_angle() const noexcept { return reference_; }

 private:
  Config config_;
  Tick started_ = 0;
  double start_angle_ = 0.0;
  double integral_ = 0.0;
  Tick stalled_for_ = 0;
  double reference_ = 0.0;
};

}  // namespace lever::fw
