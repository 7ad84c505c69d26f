#include "lever/hil/sphere3dof.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>

#include "lever/codec/receiver.hpp"
#include "lever/codec/sender.hpp"
#include "lever/common/rng.hpp"
#include "lever/hil/can_bus.hpp"

namespace lever::hil {
namespace {

constexpr double kTick = 1e-3;  // s: the device and the environment both run at 1 kHz
constexpr Nanos kTickNs = 1'000'000;

Vec3 add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec3 scale(const Vec3& a, double k) { return {a[0] * k, a[1] * k, a[2] * k}; }
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// The device can display no more than its peak force: the vector keeps its direction.
Vec3 saturate(const Vec3& f, double max_n) {
  const double m = norm(f);
  return m > max_n ? scale(f, max_n / m) : f;
}

Vec3 quantize(const Vec3& x, double resolution) {
  Vec3 q{};
  for (std::size_t i = 0; i < 3; ++i) q[i] = std::round(x[i] / resolution) * resolution;
  return q;
}

// Physiological tremor as a force: a sum of sinusoids in the tremor band per axis, each scaled by the free
// hand-and-device impedance at its frequency, so the free hand moves by the published displacement.
class Tremor {
 public:
  Tremor(const HandParams& h, double device_mass, Rng& rng) {
    const int k = std::max(h.tremor_components, 1);
    const double axis_rms = h.tremor_rms_m / std::sqrt(3.0);
    const double amplitude = axis_rms * std::sqrt(2.0 / k);
    const double m = h.mass_kg + device_mass;
    for (std::size_t axis = 0; axis < 3; ++axis) {
      for (int i = 0; i < k && i < kMax; ++i) {
        const double w = 2.0 * std::numbers::pi * rng.uniform(h.tremor_low_hz, h.tremor_high_hz);
        const double phase = rng.uniform(0.0, 2.0 * std::numbers::pi);
        const std::complex<double> impedance(h.stiffness - m * w * w, h.damping * w);
        Component& c = components_[axis][static_cast<std::size_t>(i)];
        c.phasor = impedance * std::polar(amplitude, phase);
        c.step = std::polar(1.0, w * kTick);
      }
      count_ = std::min(k, kMax);
    }
    enabled_ = h.tremor_rms_m > 0.0;
  }

  // The force now; advances by one tick.
  Vec3 next() {
    Vec3 f{};
    if (!enabled_) return f;
    for (std::size_t axis = 0; axis < 3; ++axis)
      for (int i = 0; i < count_; ++i) {
        Component& c = components_[axis][static_cast<std::size_t>(i)];
        f[axis] += c.phasor.real();
        c.phasor *= c.step;
      }
    return f;
  }

 private:
  static constexpr int kMax = 16;
  struct Component {
    std::complex<double> phasor{};
    std::complex<double> step{1.0, 0.0};
  };
  std::array<std::array<Component, kMax>, 3> components_{};
  int count_ = 0;
  bool enabled_ = false;
};

// What the person intends: strokes over the side of the sphere facing them, at a light force, now and then a
// firmer press, and after a few strokes lifting off and coming down somewhere else. Directions are great
// circles, radii and angles follow minimum-jerk profiles (Flash and Hogan), as the 1-DoF operator's reaches.
class Explorer {
 public:
  Explorer(const HandParams& h, const SphereParams& s, std::uint64_t seed) : h_(h), s_(s), rng_(seed) {
    n_from_ = n_to_ = {0.0, 0.0, 1.0};
    rho_from_ = rho_to_ = s.radius_m + 0.5 * (h.lift_min_m + h.lift_max_m);
    omega_ = 0.0;
    duration_ = 0.0;
  }

  Vec3 start() const { return add(s_.centre, scale(n_from_, rho_from_)); }

  Vec3 intent(double t) {
    if (!h_.explore) return start();
    while (t >= start_ + duration_) next_segment(start_ + duration_);
    const double tau = (t - start_) / duration_;
    const double s = tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau));
    Vec3 n;
    if (omega_ < 1e-9) {
      n = n_from_;
    } else {
      const double a = std::sin((1.0 - s) * omega_) / sin_omega_;
      const double b = std::sin(s * omega_) / sin_omega_;
      n = add(scale(n_from_, a), scale(n_to_, b));
    }
    return add(s_.centre, scale(n, rho_from_ + (rho_to_ - rho_from_) * s));
  }

 private:
  enum class Phase : std::uint8_t { descend, stroke, lift, hover };

  // Where the hand aims so a hand spring and the sphere in series settle at this force.
  double press_radius(double force) const { return s_.radius_m - force * (1.0 / h_.stiffness + 1.0 / s_.stiffness); }

  Vec3 random_direction() {
    const double cos_theta = 1.0 - rng_.uniform() * (1.0 - std::cos(h_.cap_half_angle_rad));
    const double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
    const double phi = rng_.uniform(0.0, 2.0 * std::numbers::pi);
    return {sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta};
  }

  void go(const Vec3& n_to, double rho_to, double duration) {
    n_from_ = n_to_;
    rho_from_ = rho_to_;
    n_to_ = n_to;
    rho_to_ = rho_to;
    omega_ = std::acos(std::clamp(dot(n_from_, n_to_), -1.0, 1.0));
    sin_omega_ = std::sin(omega_);
    duration_ = duration;
  }

  // A move over the surface at a speed a person strokes with; never shorter than a quick flick.
  double travel_time(const Vec3& n_to, double radius) {
    const double arc = std::acos(std::clamp(dot(n_to_, n_to), -1.0, 1.0)) * radius;
    return std::max(0.3, arc / rng_.uniform(h_.stroke_speed_min_mps, h_.stroke_speed_max_mps));
  }

  void next_segment(double now) {
    start_ = now;
    switch (phase_) {
      case Phase::descend:
        go(n_to_, press_radius(rng_.uniform(h_.stroke_force_min_n, h_.stroke_force_max_n)), rng_.uniform(0.2, 0.4));
        strokes_left_ = 2 + static_cast<int>(rng_.next() % 4);
        press_before_ = static_cast<int>(rng_.next() % static_cast<std::uint64_t>(strokes_left_));
        pressed_ = false;
        phase_ = Phase::stroke;
        return;
      case Phase::stroke:
        if (!pressed_ && strokes_left_ == press_before_) {
          pressed_ = true;
          go(n_to_, press_radius(rng_.uniform(h_.press_force_min_n, h_.press_force_max_n)), rng_.uniform(0.3, 0.8));
          return;
        }
        if (strokes_left_ > 0) {
          --strokes_left_;
          const Vec3 n = random_direction();
          go(n, press_radius(rng_.uniform(h_.stroke_force_min_n, h_.stroke_force_max_n)), travel_time(n, s_.radius_m));
          return;
        }
        go(n_to_, s_.radius_m + rng_.uniform(h_.lift_min_m, h_.lift_max_m), rng_.uniform(0.2, 0.4));
        phase_ = Phase::lift;
        return;
      case Phase::lift: {
        const Vec3 n = random_direction();
        go(n, rho_to_, travel_time(n, rho_to_));
        phase_ = Phase::hover;
        return;
      }
      case Phase::hover:
        phase_ = Phase::descend;
        next_segment(now);
        return;
    }
  }

  HandParams h_;
  SphereParams s_;
  Rng rng_;
  Phase phase_ = Phase::descend;
  int strokes_left_ = 0, press_before_ = 0;
  bool pressed_ = false;
  Vec3 n_from_{}, n_to_{};
  double rho_from_ = 0.0, rho_to_ = 0.0;
  double omega_ = 0.0, sin_omega_ = 1.0;
  double start_ = 0.0, duration_ = 0.0;
};

// The link carries each packet's sequence number in a datagram; the payload waits in the sender's table, as
// the link model needs only the datagram's timing and fate.
template <typename Payload>
class PacketTable {
 public:
  protocol::CanFrame stamp(const Payload& p) {
    const std::uint32_t seq = next_++;
    items_[seq % items_.size()] = p;
    protocol::CanFrame f;
    f.dlc = 4;
    for (std::size_t i = 0; i < 4; ++i) f.data[i] = static_cast<std::uint8_t>(seq >> (8 * i));
    return f;
  }
  const Payload& at(const protocol::CanFrame& f) const {
    std::uint32_t seq = 0;
    for (std::size_t i = 0; i < 4; ++i) seq |= static_cast<std::uint32_t>(f.data[i]) << (8 * i);
    return items_[seq % items_.size()];
  }

 private:
  // The link holds at most 4096 datagrams, so no slot is reused while its datagram is in flight.
  std::array<Payload, 4096> items_{};
  std::uint32_t next_ = 0;
};

struct UpPacket {
  double t = 0.0;
  Vec3 position{};
  codec::DeadbandSender<double, 3>::Wire velocity{};
};
struct DownPacket {
  double t = 0.0;
  codec::DeadbandSender<double, 3>::Wire force{};
};

// Packets that have arrived wait here until the receiver's clock (now minus the link's nominal delay)
// reaches their sample time: the receiver then runs the sender's model exactly, that delay late.
template <typename Payload>
class Playout {
 public:
  bool push(const Payload& p) { return queue_.push(p); }
  template <typename Accept>
  void release(double until, Accept&& accept) {
    while (!queue_.empty() && queue_.front().t <= until) {
      accept(queue_.front());
      queue_.pop();
    }
  }

 private:
  Ring<Payload, 64> queue_;
};

void validate(const SphereConfig& c) {
  auto bad = [](const char* what) { throw std::invalid_argument(std::string("sphere-3dof: ") + what); };
  if (!(c.duration_s > 0.0 && c.duration_s <= 86400.0)) bad("duration must be in (0, 86400] s");
  if (!codec::is_valid(c.velocity_codec) || !codec::is_valid(c.force_codec)) bad("invalid codec configuration");
  if (!(c.device.resolution_m > 0.0) || !(c.device.max_force_n > 0.0) || !(c.device.mass_kg >= 0.0) ||
      !(c.device.friction_n >= 0.0) || !(c.device.friction_linear_mps > 0.0))
    bad("invalid device parameters");
  if (!(c.hand.mass_kg + c.device.mass_kg > 0.0) || !(c.hand.stiffness > 0.0) || !(c.hand.damping >= 0.0) ||
      !(c.hand.tremor_rms_m >= 0.0) || !(c.hand.tremor_low_hz > 0.0) ||
      !(c.hand.tremor_high_hz >= c.hand.tremor_low_hz))
    bad("invalid hand parameters");
  if (!(c.sphere.radius_m > 0.0) || !(c.sphere.stiffness > 0.0)) bad("invalid sphere");
  if (c.substeps < 1 || c.substeps > 1000) bad("substeps must be in 1..1000");
  if (!(c.network.delay_ms >= 0.0) || !(c.network.jitter_ms >= 0.0) ||
      !(c.network.loss >= 0.0 && c.network.loss <= 1.0))
    bad("invalid network parameters");
  if (!(c.jnd >= 0.0) || !(c.jnd_absolute_n >= 0.0)) bad("invalid JND");
}

}  // namespace

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
  NetworkLink up(lan, c.seed * 4 + 1), down(lan, c.seed * 4 + 2);
  Rng tremor_rng(c.seed * 4 + 3);
  Tremor tremor(c.hand, c.device.mass_kg, tremor_rng);
  Explorer explorer(c.hand, c.sphere, c.seed * 4 + 4);

  // The link's nominal delay in ticks: a packet sent at a tick is used at the first tick at or after its
  // latest arrival. The OP side samples before the TOP computes, so a force is used one tick later at least.
  const Nanos latency_ns = static_cast<Nanos>(std::ceil((c.network.delay_ms + c.network.jitter_ms) * 1e6));
  const int up_ticks = static_cast<int>((latency_ns + kTickNs - 1) / kTickNs);
  const int down_ticks = std::max(1, up_ticks);

  codec::DeadbandSender<double, 3> velocity_sender(c.velocity_codec), force_sender(c.force_codec);
  codec::DeadbandReceiver<double, 3> velocity_receiver(c.velocity_codec.mode), force_receiver(c.force_codec.mode);
  PacketTable<UpPacket> up_table;
  PacketTable<DownPacket> down_table;
  Playout<UpPacket> up_playout;
  Playout<DownPacket> down_playout;

  const double h = kTick / c.substeps;
  const double step = h / (c.hand.mass_kg + c.device.mass_kg);  // velocity change per newton and substep
  Vec3 x = explorer.start(), v{};
  Vec3 intent = x, intent_prev = x;
  Vec3 displayed{};
  Vec3 measured_prev = quantize(x, c.device.resolution_m);

  // Histories for the delayed references (the environment's force, the measured position).
  constexpr std::size_t kHistory = 1024;
  const int max_delay = up_ticks + down_ticks;
  if (max_delay >= static_cast<int>(kHistory)) throw std::invalid_argument("sphere-3dof: link delay too long");
  std::array<Vec3, kHistory> force_history{}, measured_history{};

  bool top_has_position = false;
  Vec3 top_anchor{};  // the last received position
  double top_anchor_t = 0.0;
  double newest_up_t = -1.0, newest_down_t = -1.0;

  SphereResult r;
  const auto ticks = static_cast<std::uint64_t>(std::llround(c.duration_s / kTick));
  r.ticks = ticks;
  r.uplink_delay_ticks = up_ticks;
  r.downlink_delay_ticks = down_ticks;
  if (c.record_trace && !c.trace_sink) r.trace.reserve(ticks);
  std::uint64_t contact = 0, saturated = 0, violations = 0, downlink_violations = 0, zero_velocity = 0,
                position_samples = 0;
  double contact_force_sum = 0.0, force_sq = 0.0, position_sq = 0.0, speed_sum = 0.0;

  for (std::uint64_t k = 1; k <= ticks; ++k) {
    const double t = static_cast<double>(k) * kTick;
    const Nanos t_ns = static_cast<Nanos>(k) * kTickNs;

    // 1. The hand and the device, from the last tick to this one, under the force displayed since then.
    intent_prev = intent;
    intent = explorer.intent(t - kTick);
    const Vec3 intent_speed = scale(difference(intent, intent_prev), 1.0 / kTick);
    const Vec3 shake = tremor.next();
    for (int s = 0; s < c.substeps; ++s) {
      const double speed = norm(v);
      const double friction = c.device.friction_n / std::max(speed, c.device.friction_linear_mps);
      for (std::size_t i = 0; i < 3; ++i) {
        const double f = c.hand.stiffness * (intent[i] - x[i]) + c.hand.damping * (intent_speed[i] - v[i]) + shake[i] +
                         displayed[i] - friction * v[i];
        v[i] += f * step;
        x[i] += v[i] * h;
      }
    }
    speed_sum += norm(v);

    // 2. The OP samples the device: quantized position, velocity by backward difference (section III-E).
    const Vec3 measured = quantize(x, c.device.resolution_m);
    Vec3 velocity{};
    for (std::size_t i = 0; i < 3; ++i) velocity[i] = (measured[i] - measured_prev[i]) / kTick;
    measured_prev = measured;
    if (velocity[0] == 0.0 && velocity[1] == 0.0 && velocity[2] == 0.0) ++zero_velocity;
    const auto vd = velocity_sender.offer(t, velocity);
    if (vd.send) {
      ++r.velocity_packets;
      up.send(up_table.stamp({t, measured, vd.wire}), t_ns);
    }
    measured_history[k % kHistory] = measured;

    // 3. The OP displays the force the TOP sent, reconstructed on the TOP's clock the link's delay late.
    TimedFrame arrived;
    while (down.pop_arrived(t_ns, arrived)) {
      const DownPacket& p = down_table.at(arrived.frame);
      if (p.t <= newest_down_t || !down_playout.push(p)) {
        ++r.stale_packets;
        continue;
      }
      newest_down_t = p.t;
    }
    // Computed as the sample times are, so a sample of this clock's time compares equal to it.
    const double op_clock = static_cast<double>(static_cast<std::int64_t>(k) - down_ticks) * kTick;
    down_playout.release(op_clock, [&](const DownPacket& p) { force_receiver.receive(p.t, p.force); });
    const auto reconstructed = force_receiver.reconstruct(op_clock);
    displayed = saturate(reconstructed ? *reconstructed : Vec3{}, c.device.max_force_n);

    // 4. The TOP: the user's position from the last received position and velocity, then eq. (11).
    while (up.pop_arrived(t_ns, arrived)) {
      const UpPacket& p = up_table.at(arrived.frame);
      if (p.t <= newest_up_t || !up_playout.push(p)) {
        ++r.stale_packets;
        continue;
      }
      newest_up_t = p.t;
    }
    const double top_clock = static_cast<double>(static_cast<std::int64_t>(k) - up_ticks) * kTick;
    up_playout.release(top_clock, [&](const UpPacket& p) {
      velocity_receiver.receive(p.t, p.velocity);
      top_anchor = p.position;
      top_anchor_t = p.t;
      top_has_position = true;
    });
    Vec3 top_position{};
    Vec3 force{};
    if (top_has_position) {
      // Integral of the reconstructed velocity since the anchor: exact for both the hold and the linear model.
      const Vec3 v_anchor = velocity_receiver.model().newest().v;
      const Vec3 v_now = *velocity_receiver.reconstruct(top_clock);
      const double since = top_clock - top_anchor_t;
      top_position = add(top_anchor, scale(add(v_anchor, v_now), 0.5 * since));
      force = sphere_force(c.sphere, top_position);
    }
    const auto fd = force_sender.offer(t, force);
    if (fd.send) {
      ++r.force_packets;
      down.send(down_table.stamp({t, fd.wire}), t_ns);
    }
    force_history[k % kHistory] = force;

    // 5. Metrics: the displayed force against what a lossless p = 0 link would display now.
    const double force_n = norm(force);
    if (force_n > 0.0) {
      ++contact;
      contact_force_sum += force_n;
    }
    if (force_n > c.device.max_force_n) ++saturated;
    // Against the undistorted system: eq. (11) at the position measured the round trip earlier.
    const auto round_trip = static_cast<std::uint64_t>(up_ticks + down_ticks);
    const Vec3 reference =
        k > round_trip
            ? saturate(sphere_force(c.sphere, measured_history[(k - round_trip) % kHistory]), c.device.max_force_n)
            : Vec3{};
    const double error = norm(difference(displayed, reference));
    force_sq += error * error;
    if (error > std::max(c.jnd * norm(reference), c.jnd_absolute_n)) ++violations;
    // Against the force the TOP computed, the downlink's delay earlier: the force direction's codec alone.
    const auto downlink = static_cast<std::uint64_t>(down_ticks);
    const Vec3 sent_reference =
        k > downlink ? saturate(force_history[(k - downlink) % kHistory], c.device.max_force_n) : Vec3{};
    const double sent_error = norm(difference(displayed, sent_reference));
    if (sent_error > std::max(c.jnd * norm(sent_reference), c.jnd_absolute_n)) ++downlink_violations;
    if (top_has_position && k > static_cast<std::uint64_t>(up_ticks)) {
      const Vec3& then = measured_history[(k - static_cast<std::uint64_t>(up_ticks)) % kHistory];
      const double e = norm(difference(top_position, then));
      position_sq += e * e;
      r.position_max_error_m = std::max(r.position_max_error_m, e);
      ++position_samples;
    }
    if (c.record_trace) {
      const SphereTraceRow row{t,     x,       measured,  velocity, vd.send, top_has_position, top_position,
                               force, fd.send, displayed, reference};
      if (c.trace_sink) {
        c.trace_sink(row);
      } else {
        r.trace.push_back(row);
      }
    }
  }

  const double n = static_cast<double>(ticks);
  r.velocity_packet_rate = static_cast<double>(r.velocity_packets) / n;
  r.force_packet_rate = static_cast<double>(r.force_packets) / n;
  r.contact_share = static_cast<double>(contact) / n;
  r.mean_contact_force_n = contact > 0 ? contact_force_sum / static_cast<double>(contact) : 0.0;
  r.saturated_share = static_cast<double>(saturated) / n;
  r.force_jnd_violation = static_cast<double>(violations) / n;
  r.downlink_jnd_violation = static_cast<double>(downlink_violations) / n;
  r.force_rmse_n = std::sqrt(force_sq / n);
  r.position_rmse_m = position_samples > 0 ? std::sqrt(position_sq / static_cast<double>(position_samples)) : 0.0;
  r.zero_velocity_share = static_cast<double>(zero_velocity) / n;
  r.mean_speed_mps = speed_sum / n;
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  r.realtime_factor = r.wall_time_s > 0.0 ? c.duration_s / r.wall_time_s : 0.0;
  return r;
}

}  // namespace lever::hil
