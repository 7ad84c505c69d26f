#pragma once
// lever-hil run's report of one run (JSON or human) and its per-tick trace CSV.
#include <cstdio>
#include <nlohmann/json.hpp>

#include "lever/hil/simulation.hpp"

namespace lever::hil {

nlohmann::json report_json(const SimConfig& config, const SimResult& result);
// One direction's codec settings as every report of lever-hil writes them (run, sweep, sphere).
nlohmann::json codec_json(const codec::Config<double>& c);
// The same for a person: a few lines.
void print_report(std::FILE* out, const SimConfig& config, const SimResult& result);

// The per-tick trace CSV that run and serve write: the header line and one row, each ending in a newline.
std::string trace_csv_header();
std::string trace_csv_row(const TraceRow& row);

}  // namespace lever::hil
