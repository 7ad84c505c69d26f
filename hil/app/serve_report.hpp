#pragma once
// What lever-hil serve prints: a status line every scenario second (stderr), the per-tick trace's rows, and the
// report at the end (lever-hil run's JSON with a `serve` object, or a few human lines).
#include <cstdint>
#include <cstdio>
#include <string>

#include "bus_watch.hpp"
#include "lever/hil/devices/encoder_lines.hpp"
#include "lever/hil/simulation.hpp"
#include "serve.hpp"
#include "serve_metrics.hpp"
#include "serve_world.hpp"

namespace lever::hil {

std::string state_name(const WatchedLever& l);

void print_status_line(double t, const BusWatch& watch, const World& world, const ServeTick& s, double displayed,
                       const RunMetrics& metrics, std::int64_t max_lag_ms);

// lever-hil run's trace columns as serve sees them: `top_position_ref` is the newest position on a motion frame,
// the states are the heartbeats' (-1: none yet).
TraceRow serve_trace_row(double t, const World& world, const BusWatch& watch, const ServeTick& s, double displayed,
                         std::uint64_t motion_sent, std::uint64_t force_sent);

// The run as it ended, beside the metrics.
struct ServeSummary {
  SimConfig sim;  // duration_s: the scenario's seconds served
  SimResult result;
  std::uint64_t slips = 0;
  std::int64_t max_lag_ms = 0;
  devices::EncoderLinesStats hsi_encoder, top_encoder;
  std::uint64_t gauge_requests = 0;
  std::uint64_t can_frames_seen = 0;
};

void print_serve_report(const ServeOptions& o, const ServeSummary& summary, const ServeMetrics& metrics,
                        const ServeProbe* probe, std::FILE* out);

}  // namespace lever::hil
