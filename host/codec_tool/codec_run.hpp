#pragma once
// Runs the deadband codec (sender and a separate receiver, as on a real link) over a recorded trace.
#include <cstddef>
#include <functional>
#include <string>
#include <string_view>

#include "lever/codec/config.hpp"
#include "trace_csv.hpp"

namespace lever::tool {

struct CodecRun {
  std::size_t samples = 0;
  std::size_t sent = 0;
  double rmse = 0.0;       // RMS over samples of ||reconstruction - input||
  double max_error = 0.0;  // largest ||reconstruction - input||
};

// Receives the output CSV, t,sent,x_hat[,y_hat,z_hat] with one row per input sample, a chunk at a time.
using CsvSink = std::function<void(std::string_view)>;

CodecRun run_codec(const Trace& trace, const codec::Config<double>& config, const CsvSink& sink);

}  // namespace lever::tool
