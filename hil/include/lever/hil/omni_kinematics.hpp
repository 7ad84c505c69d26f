#pragma once
// The PHANToM Omni's position sensing: three joint encoders (base yaw, shoulder pitch, the forearm's absolute pitch
// through its parallelogram) and the forward kinematics of its two equal links, in OpenHaptics' frame (x right, y up,
// z toward the user). The tip's position is what the driver computes from the encoders' counts, in doubles: no
// Cartesian grid. docs/hil-model.md ("The position as the Omni measures it") gives the sources.
#include "lever/common/vec.hpp"

namespace lever::hil {

struct OmniJoints {
  double yaw = 0.0, shoulder = 0.0, forearm = 0.0;  // rad; all 0 with the tip at the workspace's middle
};

class OmniKinematics {
 public:
  // `middle`: the workspace's middle, where q = 0 puts the tip (upper arm horizontal toward the user, forearm
  // straight down). `counts_per_rev`: each encoder's counts per turn.
  OmniKinematics(const Vec<double, 3>& middle, double link_m, double counts_per_rev);

  OmniJoints inverse(const Vec<double, 3>& tip) const;
  Vec<double, 3> forward(const OmniJoints& q) const;
  OmniJoints quantized(const OmniJoints& q) const;
  // The position the driver reports for a tip at `tip`: its joint angles to whole counts, and back.
  Vec<double, 3> measure(const Vec<double, 3>& tip) const { return forward(quantized(inverse(tip))); }

 private:
  Vec<double, 3> shoulder_;
  double l_, counts_per_rad_;
};

}  // namespace lever::hil
