#pragma once
// What the sphere-3dof's two PCs send each other, 16 bits per DoF: the OP its measured position with the velocity
// codec's wire value, the TOP the force codec's.
#include "lever/codec/receiver.hpp"
#include "lever/codec/sender.hpp"
#include "lever/hil/sphere3dof.hpp"
#include "sphere_link.hpp"

namespace lever::hil {

using SphereSender = codec::DeadbandSender<double, 3, SphereWire>;
using SphereReceiver = codec::DeadbandReceiver<double, 3, SphereWire>;
struct UpPacket {
  double t = 0.0;
  SphereSender::Wire position{};  // sphere_position_wire()
  SphereSender::Wire velocity{};
};
struct DownPacket {
  double t = 0.0;
  SphereSender::Wire force{};
};
using Uplink = SphereChannel<UpPacket>;
using Downlink = SphereChannel<DownPacket>;

// The link's nominal delay in ticks: a packet sent at a tick is used at the first tick at or after its latest
// arrival. The OP side samples before the TOP computes, so a force is used one tick later at least.
struct SphereDelays {
  int up_ticks = 0, down_ticks = 1;
};
SphereDelays sphere_delays(const NetworkParams& network);

}  // namespace lever::hil
