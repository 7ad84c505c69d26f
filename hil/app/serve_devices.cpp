#include "serve_devices.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <numbers>
#include <string>

namespace lever::hil {

std::optional<LeverDevices> open_devices(const app::FwConfig& config, double angle, double max_edge_rate_hz) {
  LeverDevices d;
  const bool hsi = config.lever.role == protocol::Role::hsi;
  const char* who = hsi ? "HSI" : "TOP";
  d.counts_per_radian = config.lever.counts_per_rev / (2.0 * std::numbers::pi);
  d.count_origin = static_cast<std::int64_t>(std::floor(angle * d.counts_per_radian));
  const auto& encoder_config = config.board.encoder;
  devices::EncoderLinesOptions options;
  options.max_edge_rate_hz = max_edge_rate_hz;
  // The index mark sits at angle 0, as the in-process HIL's encoder has it.
  if (encoder_config.line_z) options.index_at_count = -d.count_origin;
  auto encoder = devices::EncoderLines::open(encoder_config, options);
  if (!encoder) {
    fmt::print(stderr, "lever-hil serve: {} encoder: {}\n", who, encoder.error().message);
    return std::nullopt;
  }
  d.encoder = std::move(encoder).value();
  auto motor = devices::MotorReadback::open(app::motor_config(config.board));
  if (!motor) {
    fmt::print(stderr, "lever-hil serve: {} motor: {}\n", who, motor.error().message);
    return std::nullopt;
  }
  d.motor = std::move(motor).value();
  const bool reads_gauge = !hsi || (config.lever.use_force_sensor && config.lever.display.closed_loop);
  if (reads_gauge) {
    d.gauge_config = app::gauge_config(config.board);
    if (!d.start_gauge()) return std::nullopt;
  }
  fmt::print(stderr, "lever-hil serve: {} lever: encoder {}; motor {}; gauge {}\n", who, d.encoder->description(),
             d.motor->description(), d.gauge ? d.gauge->description() : std::string("none (not read)"));
  return d;
}

void LeverDevices::stop_gauge() {
  if (!gauge) return;
  stopped_gauges_requests += gauge->counters().requests;
  gauge.reset();
}

bool LeverDevices::start_gauge() {
  if (gauge || !gauge_config) return true;
  auto started = devices::GaugeServer::open(*gauge_config);
  if (!started) {
    fmt::print(stderr, "lever-hil serve: strain gauge: {}\n", started.error().message);
    return false;
  }
  gauge = std::move(started).value();
  return true;
}

}  // namespace lever::hil
