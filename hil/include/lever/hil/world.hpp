#pragma once
// The physical world of the testbed, without any firmware: both levers' mechanics and motors, the wall at
// the TOP, and the operator's hand at the HSI. `lever-hil run` steps it beside the firmware core in simulated
// time; `lever-hil serve` steps it on the wall clock behind real lever-fw processes. Both drive it with the
// motor commands of the last millisecond and read the angles and forces back.
#include <cstdint>
#include <optional>

#include "lever/fw/hal.hpp"
#include "lever/hil/human_operator.hpp"
#include "lever/hil/lever_plant.hpp"
#include "lever/hil/wall.hpp"

namespace lever::hil {

struct WorldParams {
  ScenarioKind scenario = ScenarioKind::wall_tap;
  LeverPlantParams hsi_plant{};
  LeverPlantParams top_plant{};
  WallParams wall{};
  OperatorParams operator_params{};
  int substeps = 10;  // physics steps per 1 ms tick
  std::uint64_t operator_seed = 1;
};

class World {
 public:
  World(const WorldParams& params, double hsi_angle, double top_angle)
      : p_(params), hsi_(params.hsi_plant, hsi_angle), top_(params.top_plant, top_angle) {}

  // The operator walks up and takes the handle where the HSI now is; the scenario's clock starts at `now`.
  void start_operator(fw::Tick now) {
    operator_.emplace(p_.operator_params, p_.scenario, p_.wall.angle, hsi_.angle(), p_.operator_seed);
    start_tick_ = now;
    hsi_.set_added_inertia(p_.operator_params.hand_inertia);
  }
  bool operator_started() const { return operator_.has_value(); }

  // Whether the hand is on the handle: the operator lets go while the HSI homes, and grabs it again where it
  // then is.
  void set_hand_on(bool on, fw::Tick now) {
    on = on && operator_.has_value();
    if (on && !hand_on_) operator_->grab_at(now - start_tick_, hsi_.angle());
    if (on != hand_on_) hsi_.set_added_inertia(on ? p_.operator_params.hand_inertia : 0.0);
    hand_on_ = on;
  }
  bool hand_on() const { return hand_on_; }

  // One millisecond of physics under the motors' last commands; `after_substep` runs after each substep
  // (the encoders follow the angles at the physics' resolution, not the firmware's).
  template <typename AfterSubstep>
  void advance(const fw::MotorCommand& hsi_motor, const fw::MotorCommand& top_motor, AfterSubstep&& after_substep) {
    const double dt = 1e-3 / p_.substeps;
    for (int s = 0; s < p_.substeps; ++s) {
      const double hand_torque = hand_on_ ? operator_->torque(hsi_.angle(), hsi_.speed()) : 0.0;
      hsi_.advance(hsi_motor.torque_nm, hsi_motor.enable, hand_torque, dt);
      top_.advance(top_motor.torque_nm, top_motor.enable, wall_torque(p_.wall, top_.angle(), top_.speed()), dt);
      after_substep();
    }
  }
  void advance(const fw::MotorCommand& hsi_motor, const fw::MotorCommand& top_motor) {
    advance(hsi_motor, top_motor, [] {});
  }

  // The operator's intent moves on, from the force the hand feels now (once per tick).
  void update_operator(fw::Tick now, double felt_force_n) {
    if (operator_) operator_->update(now - start_tick_, felt_force_n);
  }

  // N: the wall pushing back on the TOP's tip, what its strain gauge measures (positive pressing into it).
  double contact_force() const { return -wall_torque(p_.wall, top_.angle(), top_.speed()) / top_.params().radius; }
  // N: the hand pushing on the HSI's handle, what a gauge in the HSI's handle measures.
  double hand_force() const { return hand_on_ ? operator_->hand_force(hsi_.angle(), hsi_.speed()) : 0.0; }

  const LeverPlant& hsi() const { return hsi_; }
  const LeverPlant& top() const { return top_; }
  const WorldParams& params() const { return p_; }

 private:
  WorldParams p_;
  LeverPlant hsi_, top_;
  std::optional<HumanOperator> operator_;
  fw::Tick start_tick_ = 0;
  bool hand_on_ = false;
};

}  // namespace lever::hil
