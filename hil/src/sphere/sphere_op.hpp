#pragma once
// The sphere-3dof's OP: the PC at the device. Every tick it reads the device (the position through its joint
// encoders and kinematics, omni_kinematics.hpp, the velocity as the driver gives it: device_velocity.hpp), sends the
// velocity through its deadband, and displays the force the TOP sent, reconstructed over the time since its update
// arrived (with op_playout: on the TOP's clock the link's delay late).
#include <cstdint>

#include "lever/codec/receiver.hpp"
#include "lever/codec/sender.hpp"
#include "lever/hil/device_velocity.hpp"
#include "lever/hil/omni_kinematics.hpp"
#include "sphere_packets.hpp"

namespace lever::hil {

class SphereOp {
 public:
  SphereOp(const SphereConfig& c, const Vec3& start, const SphereDelays& delays);

  void sample(double t, Nanos t_ns, const Vec3& position, Uplink& up);
  void display(std::uint64_t k, Nanos t_ns, Downlink& down);

  const Vec3& measured() const { return measured_; }
  const Vec3& velocity() const { return velocity_.velocity(); }
  bool velocity_sent() const { return velocity_sent_; }
  const Vec3& displayed() const { return displayed_; }
  std::uint64_t packets() const { return packets_; }

 private:
  Vec3 measure(const Vec3& tip) const;

  const SphereConfig& c_;
  int down_ticks_;
  SphereSender velocity_sender_;
  SphereReceiver force_receiver_;
  SphereWire position_wire_;
  OmniKinematics kinematics_;
  Vec3 measured_, displayed_{};
  DeviceVelocity velocity_;
  bool velocity_sent_ = false;
  std::uint64_t packets_ = 0;
  double update_t_ = 0.0, arrival_ = 0.0;  // the newest force's sample time (TOP's clock) and arrival (the OP's)
};

}  // namespace lever::hil
