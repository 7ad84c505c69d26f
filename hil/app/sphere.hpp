#pragma once
// lever-hil run's sphere-3dof scenario (the paper's 3-DoF experiment): its configuration from run's options, its
// report and trace. Kept apart from the lever scenarios' run, which drives the firmware; its sweep: sphere_sweep.hpp.
#include <nlohmann/json.hpp>
#include <string>

#include "lever/hil/simulation.hpp"
#include "lever/hil/sphere3dof.hpp"
#include "run_options.hpp"

namespace lever::hil {

// `lever-hil run`'s options as the sphere takes them: duration, seed, both codecs, the link. Lever-only options
// that were given (faults) are refused.
SphereConfig sphere_config_from(const SimConfig& run, const RunOptions& options);

nlohmann::json sphere_report_json(const SphereConfig& config, const SphereResult& result);

// Prints the report (human or JSON) and writes the trace CSV when a path is given.
int run_sphere_command(const SphereConfig& config, bool json, const std::string& trace_path);

}  // namespace lever::hil
