#include "lever/hil/hosted_rig.hpp"

#include "sim_rig.hpp"

namespace lever::hil {

namespace {
// The same setups as run_simulation, refused before any lever is made.
const SimConfig& offered(const SimConfig& config) {
  check_offered(config);
  return config;
}
}  // namespace

HostedRig::HostedRig(const SimConfig& config) : config_(offered(config)), rig_(std::make_unique<SimRig>(config_)) {}
HostedRig::~HostedRig() = default;

void HostedRig::power_up() { tick_ = rig_->power_up(); }

void HostedRig::step() { rig_->scenario_step(++tick_); }

bool HostedRig::send(const protocol::CanFrame& frame) { return rig_->host().send(frame); }

bool HostedRig::receive(TimedFrame& frame) { return rig_->host().receive(frame); }

Nanos HostedRig::now() const { return rig_->now(); }

}  // namespace lever::hil
