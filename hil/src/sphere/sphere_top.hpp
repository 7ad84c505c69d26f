#pragma once
// The sphere-3dof's TOP: the PC holding the virtual environment. Every tick it extrapolates the user's position
// from the last received position and velocity over the time since that update (IV-B-2-c), computes the sphere's
// force (eq. 11) there and sends it through its deadband. Its ticks and its clock are SphereClocks'.
#include <cstdint>

#include "lever/codec/receiver.hpp"
#include "lever/codec/sender.hpp"
#include "sphere_clocks.hpp"
#include "sphere_packets.hpp"

namespace lever::hil {

class SphereTop {
 public:
  SphereTop(const SphereConfig& c, const SphereDelays& delays, const SphereClocks& clocks);

  // The TOP's tick j: at clocks.top_tick_ns(j) on its own clock; at the OP's tick j with op_playout.
  void step(std::uint64_t j, Uplink& up, Downlink& down);

  bool has_position() const { return has_position_; }
  const Vec3& position() const { return position_; }
  const Vec3& force() const { return force_; }
  bool force_sent() const { return force_sent_; }
  std::uint64_t packets() const { return packets_; }

 private:
  void accept(const UpPacket& p);

  const SphereConfig& c_;
  const SphereClocks& clocks_;
  int up_ticks_;
  SphereReceiver velocity_receiver_;
  SphereSender force_sender_;
  SphereWire position_wire_;
  bool has_position_ = false;
  Vec3 anchor_{};          // the last received position
  double anchor_t_ = 0.0;  // its sample time, on the OP's clock
  double now_ = 0.0;       // this tick on the TOP's clock (op_playout: the OP's, the link's delay late)
  double arrival_ = 0.0;   // when the last update arrived, on the same clock (op_playout: its sample time)
  Vec3 position_{}, force_{};
  bool force_sent_ = false;
  std::uint64_t packets_ = 0;
};

}  // namespace lever::hil
