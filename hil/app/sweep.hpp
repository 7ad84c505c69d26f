#pragma once
#include <string>

#include "lever/hil/human_operator.hpp"

namespace lever::hil {

struct SweepOptions {
  ScenarioKind scenario = ScenarioKind::wall_tap;
  std::string out_dir;
  int seeds = 3;
  double duration_s = 20.0;
  int jobs = 2;
  double floor_velocity = 0.02;
  double floor_force = 0.05;
  double filter_hz = 30.0;
};

int run_sweep(const SweepOptions& options);

}  // namespace lever::hil
