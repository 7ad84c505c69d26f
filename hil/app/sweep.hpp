#pragma once
#include <string>
#include <vector>

#include "lever/hil/human_operator.hpp"
#include "lever/hil/simulation.hpp"

namespace lever::hil {

// What a sweep varies: p for each codec variant (the paper's figures), or the one-way delay with and without
// passivity (issue 14).
enum class SweepAxis { p, delay };

struct SweepOptions {
  SweepAxis over = SweepAxis::p;
  ScenarioKind scenario = ScenarioKind::wall_tap;
  std::string out_dir;
  int seeds = 3;
  double duration_s = 20.0;
  int jobs = 2;
  double floor_velocity = 0.02;
  double floor_force = 0.05;
  // The prefilter's cut-off per direction, for the filter variants; each beyond the perception range of its
  // modality (the paper's III-E): kinesthetic sensing of motion reaches about 20-30 Hz, so velocity is filtered
  // at 30 Hz; force is felt as vibration up to about 1 kHz (Pacinian corpuscles, most sensitive near 250 Hz),
  // beyond the loop's 500 Hz Nyquist, so any cut-off the 1 kHz loop can have removes what can be felt: off.
  double filter_hz_velocity = 30.0;
  double filter_hz_force = 0.0;
  // The lever p sweeps (the paper's Fig. 8): the paper's setup, both levers in one PC, its HSI closing a force loop
  // (docs/hil-model.md, "The paper's chain, choice by choice").
  // The DAD's chain: the one the loop holds the contact on (docs/hil-model.md, "The contact check").
  Topology topology = Topology::one_controller;
  GaugeChain gauge_chain = GaugeChain::dad141;
  bool hsi_force_loop = true;
  // --over delay: the one-way delays, and p for both directions (deadband, no floor or filter).
  std::vector<double> delays_ms{0.0, 10.0, 25.0, 50.0, 100.0};
  double p = 0.1;
};

int run_sweep(const SweepOptions& options);

}  // namespace lever::hil
