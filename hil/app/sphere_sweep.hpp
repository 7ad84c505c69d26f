#pragma once
// `lever-hil sweep --scenario sphere-3dof`: p from 0 to 40 % for each of the paper's three modes, a deadband on one
// direction at a time; CSV and the Fig. 12-like plots beside the paper's points.
#include "sweep.hpp"

namespace lever::hil {

int run_sphere_sweep(const SweepOptions& options);

}  // namespace lever::hil
