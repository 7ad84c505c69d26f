#include "sim_levers.hpp"

#include <stdexcept>

#include "lever/common/rng.hpp"

namespace lever::hil {
namespace {

// The firmware as the run configures it: the run's codecs, the gauge calibrated to the amplifier, and absolute
// encoders when the levers do not home.
fw::LeverConfig firmware_for(const SimConfig& config, fw::LeverConfig fw) {
  calibrate_for(fw.gauge, effective_gauge(config));
  if (!config.homing) fw.homing.method = fw::HomingMethod::absolute;
  return fw;
}

fw::LeverConfig hsi_firmware(const SimConfig& config) {
  fw::LeverConfig fw = config.hsi_firmware;
  fw.motion_codec = config.velocity_codec;
  fw.display.contact_damping_nms =
      config.hsi_contact_damping_nms.value_or(contact_settings(config).hsi_contact_damping_nms);
  return firmware_for(config, fw);
}

}  // namespace

fw::LeverConfig configured_top_firmware(const SimConfig& config) {
  fw::LeverConfig fw = config.top_firmware;
  fw.force_codec = config.force_codec;
  fw.position.reference_velocity_cutoff_hz =
      config.top_reference_cutoff_hz.value_or(contact_settings(config).top_reference_cutoff_hz);
  return firmware_for(config, fw);
}

bool reads_paper_gauge(const SimConfig& config) {
  return config.gauge_chain == GaugeChain::paper_adc ||
         (config.gauge_chain == GaugeChain::topology && config.topology == Topology::one_controller);
}

StrainGaugeParams effective_gauge(const SimConfig& config) {
  return reads_paper_gauge(config) ? paper_adc_gauge() : config.gauge;
}

ContactSettings contact_settings(const SimConfig& config) {
  // Each pair's source and the methods that chose it: docs/hil-model.md, from "The contact designed on seeds of its
  // own" to "The design's dampings within the timing budget".
  const bool paper = reads_paper_gauge(config);
  if (config.top_firmware.passivity.mode == fw::PassivityMode::tdpa) return {0.0, paper ? 0.05 : 0.6};
  return {6.25, paper ? 0.4 : 1.6};
}

PowerUpAngles power_up_angles(const SimConfig& config) {
  PowerUpAngles a;
  if (config.homing) {
    Rng start(config.seed * 4 + 6);
    a.hsi = start.uniform(-0.4, 0.25);
    a.top = start.uniform(-0.4, 0.25);
  }
  return a;
}

SimLevers::SimLevers(const SimConfig& config, const PowerUpAngles& angles, Transport& transport, const Nanos& now) {
  const StrainGaugeParams gauge = effective_gauge(config);
  if (!gauge.valid()) throw std::invalid_argument("HIL: the strain gauge's parameters are out of range");
  const fw::LeverConfig hsi_fw = hsi_firmware(config);
  const Nanos tx_delay = config.topology == Topology::one_controller ? 0 : kFirmwareTxDelay;
  hsi_ = std::make_unique<LeverSite<SimHsi>>(hsi_fw, angles.hsi, gauge, config.seed * 4 + 3, transport.hsi_bus(), now,
                                             tx_delay);
  top_ = std::make_unique<LeverSite<SimTop>>(configured_top_firmware(config), angles.top, gauge, config.seed * 4 + 4,
                                             transport.top_bus(), now, tx_delay);
  if (config.encoder_interface == EncoderInterface::counter)
    for (SimHal* hal : {&hsi_->hal, &top_->hal}) hal->encoder_.set_queue_capacity(QuadratureEncoder::kMaxQueue);
  // The HSI's own gauge only matters to a closed-loop force display; its noise costs time otherwise.
  hsi_gauge_used_ = hsi_fw.use_force_sensor && hsi_fw.display.closed_loop;
}

void SimLevers::sense(double contact_n, double hand_n, fw::Tick tick) {
  top_->hal.gauge_.update(contact_n, tick);
  if (hsi_gauge_used_) hsi_->hal.gauge_.update(hand_n, tick);
}

}  // namespace lever::hil
