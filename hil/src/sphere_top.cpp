#include "sphere_top.hpp"

#include "sphere_vec.hpp"

namespace lever::hil {
namespace {
constexpr double kTick = 1e-3;
}

SphereTop::SphereTop(const SphereConfig& c, const SphereDelays& delays)
    : c_(c),
      up_ticks_(delays.up_ticks),
      velocity_receiver_(c.velocity_codec.mode, sphere_velocity_wire()),
      force_sender_(c.force_codec, sphere_force_wire(c.device)),
      position_wire_(sphere_position_wire(c)) {}

void SphereTop::receive(std::uint64_t k, Nanos t_ns, Uplink& up) {
  clock_ = static_cast<double>(static_cast<std::int64_t>(k) - up_ticks_) * kTick;
  up.receive(t_ns, clock_, [&](const UpPacket& p) {
    velocity_receiver_.receive(p.t, p.velocity);
    for (std::size_t i = 0; i < 3; ++i) anchor_[i] = position_wire_.decode(p.position[i]);
    anchor_t_ = p.t;
    has_position_ = true;
  });
}

void SphereTop::step(std::uint64_t k, double t, Nanos t_ns, Uplink& up, Downlink& down) {
  receive(k, t_ns, up);
  position_ = {};
  force_ = {};
  if (has_position_) {
    // Integral of the reconstructed velocity since the anchor: exact for both the hold and the linear model.
    const Vec3 v_anchor = velocity_receiver_.model().newest().v;
    const Vec3 v_now = *velocity_receiver_.reconstruct(clock_);
    const double since = clock_ - anchor_t_;
    position_ = add(anchor_, scale(add(v_anchor, v_now), 0.5 * since));
    force_ = sphere_force(c_.sphere, position_);
  }
  const auto fd = force_sender_.offer(t, force_);
  force_sent_ = fd.send;
  if (fd.send) {
    ++packets_;
    down.send({t, fd.wire}, t_ns);
  }
}

}  // namespace lever::hil
