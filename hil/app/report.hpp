#pragma once
// lever-hil's JSON report of one run.
#include <nlohmann/json.hpp>

#include "lever/hil/simulation.hpp"

namespace lever::hil {

nlohmann::json report_json(const SimConfig& config, const SimResult& result);
std::string scenario_name(ScenarioKind kind);

}  // namespace lever::hil
