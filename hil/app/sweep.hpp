#pragma once
#include <string>
#include <vector>

#include "lever/codec/config.hpp"
#include "lever/hil/human_operator.hpp"
#include "lever/hil/simulation.hpp"
#include "scenario_option.hpp"

namespace lever::hil {

// What a sweep varies: p for each codec variant (the paper's figures), or the one-way delay with and without
// passivity (issue 14).
enum class SweepAxis { p, delay };

struct SweepOptions {
  SweepAxis over = SweepAxis::p;
  ScenarioOption scenario = ScenarioOption::wall_tap;
  std::string out_dir;
  int seeds = 3;
  double duration_s = 20.0;
  int jobs = 2;
  // Each direction's floor of the +floor variants and cut-off of the filter variants (each variant has its own mode,
  // each point its own p). The cut-offs are beyond the perception range of each modality (the paper's III-E):
  // kinesthetic sensing of motion reaches about 20-30 Hz, so velocity is filtered at 30 Hz; force is felt as
  // vibration up to about 1 kHz (Pacinian corpuscles, most sensitive near 250 Hz), beyond the loop's 500 Hz
  // Nyquist, so any cut-off the 1 kHz loop can have removes what can be felt: off.
  codec::Config<double> velocity_variants{codec::Mode::deadband, 0.1, 0.02, 30.0};
  codec::Config<double> force_variants{codec::Mode::deadband, 0.1, 0.05, 0.0};
  // The lever p sweeps (the paper's Fig. 8): the paper's setup, both levers in one PC, its HSI closing a force loop
  // (docs/hil-model.md, "The paper's chain, choice by choice").
  // The DAD's chain: the one the loop holds the contact on (docs/hil-model.md, "The contact check").
  Topology topology = Topology::one_controller;
  GaugeChain gauge_chain = GaugeChain::dad141;
  bool hsi_force_loop = true;
  // --over delay: the one-way delays, and both directions' codec (deadband, no floor or filter; p an option).
  std::vector<double> delays_ms{0.0, 10.0, 25.0, 50.0, 100.0};
  codec::Config<double> delay_codec;
};

int run_sweep(const SweepOptions& options);

}  // namespace lever::hil
