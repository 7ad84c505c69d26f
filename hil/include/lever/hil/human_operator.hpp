#pragma once
// The operator at the HSI: an arm modelled as a mass-spring-damper around an intended lever angle. The
// intent follows the scenario's segments: position segments (reach, tap, release) by minimum-jerk motion,
// force segments (press, hold) by a slow force loop on the force the hand feels, with a reaction delay.
#include <array>
#include <cstdint>
#include <string_view>

#include "lever/common/rng.hpp"
#include "lever/fw/tick.hpp"

namespace lever::hil {

struct OperatorParams {
  double hand_inertia = 3e-3;       // kg m^2: about 0.3 kg of hand and forearm at the 0.1 m handle
  double stiffness = 3.0;           // N m/rad: 300 N/m at the handle, a relaxed grip (Hogan's arm impedance range)
  double damping = 0.2;             // N m s/rad: near-critical for the hand on the lever
  double arm = 0.1;                 // m: handle radius, for torque <-> force
  int reaction_delay_ticks = 60;    // ms: spinal/cortical force-loop delay
  double force_bandwidth_hz = 1.5;  // how fast a person corrects a felt force error
  // Factors on the scenario script's documented ranges (docs/hil-model.md, "Scenarios"), for sweeps: every move
  // takes its time over speed_factor, every pause at the end of a move its time times dwell_factor.
  double speed_factor = 1.0;
  double dwell_factor = 1.0;
};

// The operator's scripts on the levers. The paper's 3-DoF experiment has no lever and a simulator of its own
// (lever/hil/sphere3dof.hpp); lever-hil's --scenario names both (hil/app/scenario_option.hpp).
enum class ScenarioKind : std::uint8_t { wall_tap, free_motion, press_hold };
inline constexpr ScenarioKind kAllScenarios[] = {ScenarioKind::wall_tap, ScenarioKind::free_motion,
                                                 ScenarioKind::press_hold};
constexpr std::string_view name(ScenarioKind k) {
  return k == ScenarioKind::wall_tap ? "wall-tap" : k == ScenarioKind::free_motion ? "free-motion" : "press-hold";
}

// One piece of intent.
struct Segment {
  enum class Kind : std::uint8_t { move, press } kind = Kind::move;
  double target_angle = 0.0;  // move: rad
  double target_force = 0.0;  // press: N
  double duration_s = 1.0;    // includes any dwell at the end of a move
  double move_s = 1.0;        // move: time to reach the target (<= duration)
};

class HumanOperator {
 public:
  HumanOperator(const OperatorParams& p, ScenarioKind scenario, double wall_angle, double start_angle,
                std::uint64_t seed);

  // Once per tick: advance the intent. felt_force is the force the hand feels now (N, pushing positive).
  void update(fw::Tick now, double felt_force);

  // The hand takes the handle again where it now is (after letting go while the lever homed), and goes on
  // with a fresh piece of intent from there instead of yanking the lever to where the old one had got to.
  void grab_at(fw::Tick now, double angle);

  // Torque on the lever at the current state (called at every physics substep).
  double torque(double angle, double speed) const {
    return p_.stiffness * (intent_angle_ - angle) + p_.damping * (intent_speed_ - speed);
  }
  // The force the hand exerts through the handle, in newtons.
  double hand_force(double angle, double speed) const { return torque(angle, speed) / p_.arm; }

  double intent_angle() const { return intent_angle_; }
  const Segment& segment() const { return segment_; }
  const OperatorParams& params() const { return p_; }

 private:
  Segment next_segment();
  void start(const Segment& s, double now_s);

  OperatorParams p_;
  ScenarioKind scenario_;
  double wall_;
  Rng rng_;
  Segment segment_;
  double segment_start_s_ = 0.0;
  double move_from_ = 0.0;
  double intent_angle_ = 0.0;
  double intent_speed_ = 0.0;
  int script_step_ = 0;
  int taps_left_ = 0;
  std::array<double, 256> felt_history_{};
  std::size_t felt_head_ = 0;
};

}  // namespace lever::hil
