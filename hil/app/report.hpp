#pragma once
// lever-hil's JSON report of one run.
#include <nlohmann/json.hpp>

#include "lever/hil/simulation.hpp"

namespace lever::hil {

nlohmann::json report_json(const SimConfig& config, const SimResult& result);
std::string scenario_name(ScenarioKind kind);

// The per-tick trace CSV that run and serve write: the header line and one row, each ending in a newline.
std::string trace_csv_header();
std::string trace_csv_row(const TraceRow& row);

}  // namespace lever::hil
