#pragma once
// The sphere-3dof's TOP: the PC holding the virtual environment. Every tick it extrapolates the user's position
// from the last received position and velocity, the link's delay late, computes the sphere's force (eq. 11) there
// and sends it through its deadband.
#include <cstdint>

#include "lever/codec/receiver.hpp"
#include "lever/codec/sender.hpp"
#include "sphere_packets.hpp"

namespace lever::hil {

class SphereTop {
 public:
  SphereTop(const SphereConfig& c, const SphereDelays& delays);

  void step(std::uint64_t k, double t, Nanos t_ns, Uplink& up, Downlink& down);

  bool has_position() const { return has_position_; }
  const Vec3& position() const { return position_; }
  const Vec3& force() const { return force_; }
  bool force_sent() const { return force_sent_; }
  std::uint64_t packets() const { return packets_; }

 private:
  void receive(std::uint64_t k, Nanos t_ns, Uplink& up);

  const SphereConfig& c_;
  int up_ticks_;
  SphereReceiver velocity_receiver_;
  SphereSender force_sender_;
  SphereWire position_wire_;
  bool has_position_ = false;
  Vec3 anchor_{};  // the last received position
  double anchor_t_ = 0.0;
  double clock_ = 0.0;  // the OP's clock the link's delay late
  Vec3 position_{}, force_{};
  bool force_sent_ = false;
  std::uint64_t packets_ = 0;
};

}  // namespace lever::hil
