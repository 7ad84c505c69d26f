#pragma once
// `lever-hil study`: one session of the paper's user study on the HIL's simulated pair, answered by a simulated
// observer, written to a session log as lever-study's runner writes one (docs/study.md, "Sessions on the HIL").
#include <CLI/CLI.hpp>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lever/hil/simulation.hpp"
#include "lever/study/rating.hpp"
#include "lever/study/three_ifc.hpp"

namespace lever::hil {

struct StudyOptions {
  std::string log;
  std::string protocol = "3ifc";
  std::string subject = "sim";
  std::uint64_t seed = 1;
  std::optional<double> interval_s;  // default: the protocol's, the paper's 20 s (3ifc) or 30 s (rating)
  study::ThreeIfcConfig three_ifc;
  study::RatingConfig rating;
  double threshold = 0.12, slope = 3.0, lapse = 0.02;  // the 3IFC observer (Weibull), as lever-study's
  // Fig. 8's setup, the one the contact check passes in one controller (docs/hil-model.md, "The contact check"):
  // both levers in one PC, the DAD 141.1 chain, the HSI's force loop on its gauge.
  Topology topology = Topology::one_controller;
  GaugeChain gauge_chain = GaugeChain::dad141;
  bool hsi_force_loop = true;
  double confirm_timeout_s = 1.0;
  std::vector<const CLI::Option*> three_ifc_only;  // refused with --protocol rating, which would ignore them
};

void add_study_options(CLI::App& cmd, StudyOptions& o);
// 0 the session is in the log; throws std::invalid_argument for bad input, std::runtime_error for a simulated pair
// that would not carry the session (never armed, never confirming).
int run_study(const StudyOptions& o);

}  // namespace lever::hil
