#include "lever/hil/sphere3dof.hpp"

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "sphere_clocks.hpp"
#include "sphere_device.hpp"
#include "sphere_metrics.hpp"
#include "sphere_op.hpp"
#include "sphere_packets.hpp"
#include "sphere_top.hpp"
#include "sphere_vec.hpp"

namespace lever::hil {
namespace {

constexpr double kTick = 1e-3;  // s: the device and the environment both run at 1 kHz
constexpr Nanos kTickNs = 1'000'000;

void validate(const SphereConfig& c) {
  auto bad = [](const char* what) { throw std::invalid_argument(std::string("sphere-3dof: ") + what); };
  if (!(c.duration_s > 0.0 && c.duration_s <= 86400.0)) bad("duration must be in (0, 86400] s");
  if (!codec::is_valid(c.velocity_codec) || !codec::is_valid(c.force_codec)) bad("invalid codec configuration");
  if (!(c.device.resolution_m > 0.0) || !(c.device.max_force_n > 0.0) || !(c.device.mass_kg >= 0.0) ||
      !(c.device.friction_n >= 0.0) || !(c.device.friction_linear_mps > 0.0) ||
      !(c.device.encoder_counts_per_rev >= 1.0) || !(c.device.link_m > 0.0))
    bad("invalid device parameters");
  if (!(c.hand.mass_kg + c.device.mass_kg > 0.0) || !(c.hand.stiffness > 0.0) || !(c.hand.damping >= 0.0) ||
      !(c.hand.tremor_rms_m >= 0.0) || !(c.hand.tremor_low_hz > 0.0) ||
      !(c.hand.tremor_high_hz >= c.hand.tremor_low_hz))
    bad("invalid hand parameters");
  if (!(c.sphere.radius_m > 0.0) || !(c.sphere.stiffness > 0.0)) bad("invalid sphere");
  if (c.substeps < 1 || c.substeps > 1000) bad("substeps must be in 1..1000");
  if (!(c.driver_cutoff_hz > 0.0 && c.driver_cutoff_hz < 500.0)) bad("the driver's cut-off must be in (0, 500) Hz");
  if (!(c.network.delay_ms >= 0.0) || !(c.network.jitter_ms >= 0.0) ||
      !(c.network.loss >= 0.0 && c.network.loss <= 1.0))
    bad("invalid network parameters");
  if (!(c.jnd >= 0.0) || !(c.jnd_absolute_n >= 0.0)) bad("invalid JND");
  if (!(c.top_clock_drift_ppm_max >= 0.0 && c.top_clock_drift_ppm_max <= 10000.0))
    bad("the TOP clock's drift range must be in [0, 10000] ppm");
}

void record(const SphereConfig& c, SphereResult& r, double t, const SphereDevice& device, const SphereOp& op,
            const SphereTop& top, const SphereMetrics& metrics) {
  const SphereTraceRow row{t,
                           device.position(),
                           op.measured(),
                           op.velocity(),
                           op.velocity_sent(),
                           top.has_position(),
                           top.position(),
                           top.force(),
                           top.force_sent(),
                           op.displayed(),
                           metrics.reference()};
  if (c.trace_sink) {
    c.trace_sink(row);
  } else {
    r.trace.push_back(row);
  }
}

}  // namespace

SphereDelays sphere_delays(const NetworkParams& network) {
  const Nanos latency_ns = static_cast<Nanos>(std::ceil((network.delay_ms + network.jitter_ms) * 1e6));
  const int up_ticks = static_cast<int>((latency_ns + kTickNs - 1) / kTickNs);
  return {up_ticks, std::max(1, up_ticks)};
}

Vec3 sphere_force(const SphereParams& sphere, const Vec3& x) {
  const Vec3 d = difference(x, sphere.centre);
  const double distance = norm(d);
  if (!(distance < sphere.radius_m) || distance == 0.0) return {};
  return scale(d, (sphere.radius_m - distance) * sphere.stiffness / distance);
}

SphereConfig sphere_variant(SphereDirection direction, codec::Mode mode, bool filter, double p) {
  SphereConfig c;
  const codec::Config<double> every_change{codec::Mode::deadband, 0.0, 0.0, 0.0};
  if (direction == SphereDirection::velocity) {
    c.velocity_codec = {mode, p, 0.0, filter ? kSphereVelocityFilterHz : 0.0};
    c.force_codec = every_change;
  } else {
    c.velocity_codec = every_change;
    c.force_codec = {mode, p, 0.0, filter ? kSphereForceFilterHz : 0.0};
  }
  return c;
}

SphereResult run_sphere(const SphereConfig& c) {
  validate(c);
  const auto wall_start = std::chrono::steady_clock::now();
  NetworkParams lan = c.network;
  lan.reorder = false;
  Uplink up(lan, c.seed * 4 + 1);
  Downlink down(lan, c.seed * 4 + 2);
  SphereDevice device(c);
  const SphereDelays delays = sphere_delays(c.network);
  const SphereClocks clocks(c, delays);
  SphereOp op(c, device.start(), delays);
  SphereTop top(c, delays, clocks);
  SphereMetrics metrics(c, delays, clocks);
  const bool own_clock = c.top_clock == SphereTopClock::own;
  std::uint64_t top_ticks = 0;  // the TOP's ticks run so far: the next is top_ticks
  std::uint64_t force_in_contact = 0;
  auto top_step = [&](std::uint64_t j) {
    top.step(j, up, down);
    metrics.top_stepped(j, top);
    if (norm(top.force()) > 0.0) force_in_contact += top.force_sent() ? 1 : 0;
    ++top_ticks;
  };

  SphereResult r;
  const auto ticks = static_cast<std::uint64_t>(std::llround(c.duration_s / kTick));
  if (c.record_trace && !c.trace_sink) r.trace.reserve(static_cast<std::size_t>(ticks));
  std::uint64_t velocity_in_contact = 0;
  for (std::uint64_t k = 1; k <= ticks; ++k) {
    const double t = static_cast<double>(k) * kTick;
    const Nanos t_ns = static_cast<Nanos>(k) * kTickNs;
    // On its own clock the TOP runs every tick of its own that falls before this one of the OP's.
    while (own_clock && clocks.top_tick_ns(top_ticks) < t_ns) top_step(top_ticks);
    device.step(t, op.displayed());
    op.sample(t, t_ns, device.position(), up);
    metrics.op_sampled(k, op);
    op.display(k, t_ns, down);
    if (!own_clock) top_step(k);
    metrics.step(k, op, top, device.speed());
    if (norm(top.force()) > 0.0) velocity_in_contact += op.velocity_sent() ? 1 : 0;
    if (c.record_trace) record(c, r, t, device, op, top, metrics);
  }

  r.ticks = ticks;
  r.uplink_delay_ticks = delays.up_ticks;
  r.downlink_delay_ticks = delays.down_ticks;
  r.velocity_packets = op.packets();
  r.force_packets = top.packets();
  r.stale_packets = up.stale() + down.stale();
  r.top_clock_phase_ms = clocks.phase_ms();
  r.top_clock_drift_ppm = clocks.drift_ppm();
  r.top_ticks = top_ticks;
  r.velocity_packet_rate = static_cast<double>(r.velocity_packets) / static_cast<double>(ticks);
  r.force_packet_rate = static_cast<double>(r.force_packets) / static_cast<double>(ticks);
  r.velocity_contact_rate = static_cast<double>(velocity_in_contact) / static_cast<double>(ticks);
  r.force_contact_rate = static_cast<double>(force_in_contact) / static_cast<double>(ticks);
  metrics.finish(r, ticks);
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  r.realtime_factor = r.wall_time_s > 0.0 ? c.duration_s / r.wall_time_s : 0.0;
  return r;
}

}  // namespace lever::hil
