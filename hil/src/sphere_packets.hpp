#pragma once
// What the sphere-3dof's two PCs send each other: the OP its measured position with the velocity codec's wire
// value, the TOP the force codec's.
#include "lever/codec/sender.hpp"
#include "lever/hil/sphere3dof.hpp"
#include "sphere_link.hpp"

namespace lever::hil {

struct UpPacket {
  double t = 0.0;
  Vec3 position{};
  codec::DeadbandSender<double, 3>::Wire velocity{};
};
struct DownPacket {
  double t = 0.0;
  codec::DeadbandSender<double, 3>::Wire force{};
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
