#pragma once
#include "sweep.hpp"

namespace lever::hil {

// `lever-hil sweep --over delay`: wall-tap over two sites at each one-way delay, without passivity (observe: the
// same control as off, with the observer running) and with tdpa; CSV and PNG plots (docs/firmware.md,
// "Passivity under delay").
int run_delay_sweep(const SweepOptions& options);

}  // namespace lever::hil
