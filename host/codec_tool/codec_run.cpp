#include "codec_run.hpp"

#include <fmt/format.h>

#include <cmath>
#include <iterator>
#include <stdexcept>
#include <string_view>

#include "lever/codec/codec.hpp"

namespace lever::tool {
namespace {

// The output goes to the sink in chunks of about this size: memory stays bounded however long the trace.
constexpr std::size_t kChunkBytes = 64 * 1024;

template <std::size_t N>
CodecRun run(const Trace& trace, const codec::Config<double>& config, const CsvSink& sink) {
  codec::DeadbandSender<double, N> sender(config);
  codec::DeadbandReceiver<double, N> receiver(config.mode);

  CodecRun result;
  result.samples = trace.samples();
  fmt::memory_buffer out;
  const std::string_view header = N == 1 ? "t,sent,x_hat\n" : "t,sent,x_hat,y_hat,z_hat\n";
  out.append(header.data(), header.data() + header.size());
  double squared_error_sum = 0.0;
  for (std::size_t i = 0; i < trace.samples(); ++i) {
    const double t = trace.t[i];
    Vec<double, N> x;
    for (std::size_t d = 0; d < N; ++d) x[d] = trace.row(i)[d];

    const auto decision = sender.offer(t, x);
    if (decision.send) {
      receiver.receive(t, decision.wire);
      ++result.sent;
    }
    // The first sample is always sent, so the receiver always has a reconstruction here.
    const Vec<double, N> x_hat = *receiver.reconstruct(t);

    const double error = norm(difference(x_hat, x));
    squared_error_sum += error * error;
    if (error > result.max_error) result.max_error = error;

    fmt::format_to(std::back_inserter(out), "{:.17g},{:d}", t, decision.send ? 1 : 0);
    for (std::size_t d = 0; d < N; ++d) fmt::format_to(std::back_inserter(out), ",{:.17g}", x_hat[d]);
    out.push_back('\n');
    if (out.size() > kChunkBytes) {
      sink({out.data(), out.size()});
      out.clear();
    }
  }
  sink({out.data(), out.size()});
  result.rmse = std::sqrt(squared_error_sum / static_cast<double>(result.samples));
  return result;
}

}  // namespace

CodecRun run_codec(const Trace& trace, const codec::Config<double>& config, const CsvSink& sink) {
  if (!codec::is_valid(config)) throw std::invalid_argument("invalid codec configuration");
  switch (trace.dof) {
    case 1:
      return run<1>(trace, config, sink);
    case 3:
      return run<3>(trace, config, sink);
    default:
      throw std::invalid_argument(fmt::format("unsupported DoF count {}", trace.dof));
  }
}

}  // namespace lever::tool
