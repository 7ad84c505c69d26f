#pragma once
// Both levers of lever-hil run, each the real firmware core on a simulated board at its site: configured for the
// run, powered up at their angles, their gauges fed and their firmware stepped every tick.
#include <memory>

#include "lever/hil/simulation.hpp"
#include "lever/hil/world.hpp"
#include "lever_site.hpp"
#include "transport.hpp"

namespace lever::hil {

// Where the levers power up: anywhere in the working range with homing, the operator's start angle without.
struct PowerUpAngles {
  double hsi = 0.1, top = 0.1;
};
PowerUpAngles power_up_angles(const SimConfig& config);

// The TOP's firmware as the run configures it: the run's force codec, its contact settings, the gauge calibrated.
fw::LeverConfig configured_top_firmware(const SimConfig& config);

class SimLevers {
 public:
  SimLevers(const SimConfig& config, const PowerUpAngles& angles, Transport& transport, const Nanos& now);

  // After each physics substep: the encoders follow the angles at the physics' resolution.
  void track(const World& world) {
    hsi_->hal.encoder_.track(world.hsi().angle());
    top_->hal.encoder_.track(world.top().angle());
  }
  // The gauges take this tick's forces: the wall's at the TOP, the hand's at the HSI when its display reads it.
  void sense(double contact_n, double hand_n, fw::Tick tick);
  void step(fw::Tick tick) {
    hsi_->step(tick);
    top_->step(tick);
  }
  // In one controller: both levers sample (and send), then the transport hands over the frames, then both act.
  void sample(fw::Tick tick) {
    hsi_->sample(tick);
    top_->sample(tick);
  }
  void act(fw::Tick tick) {
    hsi_->act(tick);
    top_->act(tick);
  }

  bool both_armed() const { return hsi_->lever->supervisor().armed() && top_->lever->supervisor().armed(); }
  SimView view(double t, fw::Tick tick) const {
    return {t, tick, *hsi_->lever, *top_->lever, hsi_->rearms_sent, top_->rearms_sent};
  }
  LeverSite<SimHsi>& hsi() { return *hsi_; }
  LeverSite<SimTop>& top() { return *top_; }
  const LeverSite<SimHsi>& hsi() const { return *hsi_; }
  const LeverSite<SimTop>& top() const { return *top_; }

 private:
  // Levers live at a fixed address: the core holds a reference to its HAL.
  std::unique_ptr<LeverSite<SimHsi>> hsi_;
  std::unique_ptr<LeverSite<SimTop>> top_;
  bool hsi_gauge_used_;
};

}  // namespace lever::hil
