#include "sphere_op.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "sphere_vec.hpp"

namespace lever::hil {
namespace {
constexpr double kTick = 1e-3;
}  // namespace

SphereOp::SphereOp(const SphereConfig& c, const Vec3& start, const SphereDelays& delays)
    : c_(c),
      down_ticks_(delays.down_ticks),
      velocity_sender_(c.velocity_codec, sphere_velocity_wire()),
      force_receiver_(c.force_codec.mode, sphere_force_wire(c.device)),
      position_wire_(sphere_position_wire(c)),
      kinematics_(c.sphere.centre, c.device.link_m, c.device.encoder_counts_per_rev),
      measured_(measure(start)),
      velocity_(c, measured_) {}

void SphereOp::sample(double t, Nanos t_ns, const Vec3& position, Uplink& up) {
  measured_ = measure(position);
  const auto vd = velocity_sender_.offer(t, velocity_.update(measured_));
  velocity_sent_ = vd.send;
  if (vd.send) {
    ++packets_;
    UpPacket packet{t, {}, vd.wire};
    bool clipped = false;
    for (std::size_t i = 0; i < 3; ++i) packet.position[i] = position_wire_.encode(measured_[i], clipped);
    up.send(packet, t_ns);
  }
}

Vec3 SphereOp::measure(const Vec3& tip) const {
  switch (c_.position_sensor) {
    case SpherePositionSensor::cartesian_grid:
      return quantize(tip, c_.device.resolution_m);
    case SpherePositionSensor::exact:
      return tip;
    case SpherePositionSensor::joint_encoders:
      break;
  }
  return kinematics_.measure(tip);
}

void SphereOp::display(std::uint64_t k, Nanos t_ns, Downlink& down) {
  std::optional<Vec3> reconstructed;
  if (c_.top_clock == SphereTopClock::own) {
    // The TOP's model on the TOP's sample times, evaluated the time elapsed here since the newest update arrived.
    const double t = static_cast<double>(k) * kTick;
    down.receive_on_arrival(t_ns, [&](const DownPacket& p, Nanos arrival_ns) {
      force_receiver_.receive(p.t, p.force);
      update_t_ = p.t;
      arrival_ = static_cast<double>(arrival_ns) * 1e-9;
    });
    reconstructed = force_receiver_.reconstruct(update_t_ + std::max(0.0, t - arrival_));
  } else {
    // Computed as the sample times are, so a sample of this clock's time compares equal to it.
    const double op_clock = static_cast<double>(static_cast<std::int64_t>(k) - down_ticks_) * kTick;
    down.receive(t_ns, op_clock, [&](const DownPacket& p) { force_receiver_.receive(p.t, p.force); });
    reconstructed = force_receiver_.reconstruct(op_clock);
  }
  displayed_ = saturate(reconstructed ? *reconstructed : Vec3{}, c_.device.max_force_n);
}

}  // namespace lever::hil
