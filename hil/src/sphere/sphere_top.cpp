#include "sphere_top.hpp"

#include <algorithm>

#include "sphere_vec.hpp"

namespace lever::hil {
namespace {
constexpr double kTick = 1e-3;
constexpr Nanos kTickNs = 1'000'000;
}  // namespace

SphereTop::SphereTop(const SphereConfig& c, const SphereDelays& delays, const SphereClocks& clocks)
    : c_(c),
      clocks_(clocks),
      up_ticks_(delays.up_ticks),
      velocity_receiver_(c.velocity_codec.mode, sphere_velocity_wire()),
      force_sender_(c.force_codec, sphere_force_wire(c.device)),
      position_wire_(sphere_position_wire(c)) {}

void SphereTop::accept(const UpPacket& p) {
  velocity_receiver_.receive(p.t, p.velocity);
  for (std::size_t i = 0; i < 3; ++i) anchor_[i] = position_wire_.decode(p.position[i]);
  anchor_t_ = p.t;
  has_position_ = true;
}

void SphereTop::step(std::uint64_t j, Uplink& up, Downlink& down) {
  const bool own = c_.top_clock == SphereTopClock::own;
  const double t = static_cast<double>(j) * kTick;
  const Nanos t_ns = own ? clocks_.top_tick_ns(j) : static_cast<Nanos>(j) * kTickNs;
  if (own) {
    now_ = t;
    up.receive_on_arrival(t_ns, [&](const UpPacket& p, Nanos arrival_ns) {
      accept(p);
      arrival_ = clocks_.top_clock_at(arrival_ns);
    });
  } else {
    now_ = static_cast<double>(static_cast<std::int64_t>(j) - up_ticks_) * kTick;
    up.receive(t_ns, now_, [&](const UpPacket& p) {
      accept(p);
      arrival_ = p.t;
    });
  }
  position_ = {};
  force_ = {};
  if (has_position_) {
    // Integral of the reconstructed velocity since the update: exact for both the hold and the linear model. The
    // sender's model runs on the sender's sample times (its slope stays coherent) and is evaluated the elapsed time
    // past the update's sample.
    const double since = std::max(0.0, now_ - arrival_);
    const Vec3 v_anchor = velocity_receiver_.model().newest().v;
    const Vec3 v_now = *velocity_receiver_.reconstruct(own ? anchor_t_ + since : now_);
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
