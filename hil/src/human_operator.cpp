#include "lever/hil/human_operator.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace lever::hil {
namespace {

// Minimum-jerk blend (Flash and Hogan 1985): position and its time derivative factor.
double minimum_jerk(double tau) {
  tau = std::clamp(tau, 0.0, 1.0);
  return tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau));
}
double minimum_jerk_rate(double tau) {
  if (tau <= 0.0 || tau >= 1.0) return 0.0;
  return 30.0 * tau * tau * (1.0 - tau) * (1.0 - tau);
}

}  // namespace

HumanOperator::HumanOperator(const OperatorParams& p, ScenarioKind scenario, double wall_angle, double start_angle,
                             std::uint64_t seed)
    : p_(p), scenario_(scenario), wall_(wall_angle), rng_(seed), intent_angle_(start_angle) {
  if (!(p.speed_factor > 0.0) || !std::isfinite(p.speed_factor) || !(p.dwell_factor >= 0.0) ||
      !std::isfinite(p.dwell_factor))
    throw std::invalid_argument("the operator's speed factor must be > 0 and its dwell factor >= 0");
  move_from_ = start_angle;
  start(next_segment(), 0.0);
}

void HumanOperator::start(const Segment& s, double now_s) {
  segment_ = s;
  segment_start_s_ = now_s;
  move_from_ = intent_angle_;
}

void HumanOperator::grab_at(fw::Tick now, double angle) {
  intent_angle_ = angle;
  intent_speed_ = 0.0;
  // First back to the working range at an unhurried pace, as a person would before tapping again.
  const double target = rng_.uniform(0.05, 0.2);
  start(Segment{Segment::Kind::move, target, 0.0, 1.3, 1.0}, static_cast<double>(now) * 1e-3);
}

void HumanOperator::update(fw::Tick now, double felt_force) {
  const double now_s = static_cast<double>(now) * 1e-3;
  felt_history_[felt_head_] = felt_force;
  felt_head_ = (felt_head_ + 1) % felt_history_.size();
  while (now_s - segment_start_s_ >= segment_.duration_s) start(next_segment(), segment_start_s_ + segment_.duration_s);

  const double elapsed = now_s - segment_start_s_;
  if (segment_.kind == Segment::Kind::move) {
    const double tau = elapsed / segment_.move_s;
    intent_angle_ = move_from_ + (segment_.target_angle - move_from_) * minimum_jerk(tau);
    intent_speed_ = (segment_.target_angle - move_from_) * minimum_jerk_rate(tau) / segment_.move_s;
    return;
  }
  // Press: push the intent further until the force felt (as it was a reaction time ago) reaches the target.
  // Gain: felt force changes by stiffness/arm per radian of intent against a rigid wall, so this gain gives a
  // first-order force loop at force_bandwidth_hz.
  const std::size_t delay = static_cast<std::size_t>(p_.reaction_delay_ticks);
  const double felt_then = felt_history_[(felt_head_ + felt_history_.size() - 1 - delay) % felt_history_.size()];
  const double gain = 2.0 * std::numbers::pi * p_.force_bandwidth_hz * p_.arm / p_.stiffness;
  intent_speed_ = gain * (segment_.target_force - felt_then);
  intent_angle_ += intent_speed_ * 1e-3;
}

// The scenarios' scripts. Ranges describe what people do on a desk-top lever; docs/hil-model.md says why.
// A call takes one draw in its arguments at most: C++ leaves their order open, and GCC evaluates them right to left
// on x86-64 and left to right on Arm, which made the same seed another run there. The others are drawn before, in
// x86-64's order (last argument first), so that its runs stay what they were.
Segment HumanOperator::next_segment() {
  // Factors of 1 leave every time exactly as drawn, so the default runs keep their bytes.
  auto move = [this](double target, double move_s, double dwell_s) {
    const double m = move_s / p_.speed_factor;
    return Segment{Segment::Kind::move, target, 0.0, m + dwell_s * p_.dwell_factor, m};
  };
  switch (scenario_) {
    case ScenarioKind::free_motion:
      // Reaching back and forth, never as far as the wall.
      {
        const double dwell = rng_.uniform(0.0, 0.3);
        const double move_s = rng_.uniform(0.3, 1.0);
        return move(rng_.uniform(0.0, wall_ - 0.08), move_s, dwell);
      }
    case ScenarioKind::press_hold:
      switch (script_step_++ % 3) {
        case 0:
          return move(wall_ - 0.02, rng_.uniform(0.4, 0.7), 0.1);
        case 1:
          return Segment{Segment::Kind::press, 0.0, rng_.uniform(3.0, 6.0), rng_.uniform(2.0, 4.0), 0.0};
        default: {
          const double dwell = rng_.uniform(0.5, 1.0);
          const double move_s = rng_.uniform(0.3, 0.6);
          return move(rng_.uniform(0.05, 0.15), move_s, dwell);
        }
      }
    case ScenarioKind::wall_tap:
      // The paper's 1-DoF task: feel the wall by tapping it and pressing against it.
      if (taps_left_ > 0) {
        // A tap is a quick thrust past the surface and back: the wall stops the lever, the hand rebounds.
        const bool thrust = taps_left_ % 2 == 0;
        --taps_left_;
        if (thrust) {
          const double move_s = rng_.uniform(0.10, 0.15);
          return move(wall_ + rng_.uniform(0.02, 0.05), move_s, 0.0);
        }
        const double dwell = rng_.uniform(0.0, 0.1);
        const double move_s = rng_.uniform(0.12, 0.2);
        return move(wall_ - rng_.uniform(0.03, 0.08), move_s, dwell);
      }
      switch (script_step_++ % 4) {
        case 0: {
          const double dwell = rng_.uniform(0.1, 0.4);
          const double move_s = rng_.uniform(0.4, 0.8);
          return move(rng_.uniform(0.05, 0.2), move_s, dwell);
        }
        case 1: {
          taps_left_ = 2 * static_cast<int>(1 + rng_.next() % 3) - 1;  // this thrust plus 0-2 more taps
          const double move_s = rng_.uniform(0.10, 0.15);
          return move(wall_ + rng_.uniform(0.02, 0.05), move_s, 0.0);
        }
        case 2:
          return move(wall_ - 0.02, 0.2, 0.0);
        default:
          return Segment{Segment::Kind::press, 0.0, rng_.uniform(2.0, 8.0), rng_.uniform(0.6, 1.5), 0.0};
      }
  }
  return move(0.1, 1.0, 0.0);
}

}  // namespace lever::hil
