#pragma once
// Example traces from simple physics, for the demo, the README's rate table and tests.
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

#include "trace_csv.hpp"

namespace lever::tool {

enum class TraceKind {
  velocity,  // lever velocity by backward difference of a 16384-count encoder, operator tapping a stiff wall
  force,     // the same lever's contact force through a noisy 16-bit strain gauge
  force3,    // 3-DoF contact force of a cursor exploring a virtual sphere (paper eq. 11)
};
inline constexpr TraceKind kAllTraceKinds[] = {TraceKind::velocity, TraceKind::force, TraceKind::force3};
constexpr std::string_view name(TraceKind k) {
  return k == TraceKind::velocity ? "velocity" : k == TraceKind::force ? "force" : "force3";
}

struct GeneratorOptions {
  TraceKind kind = TraceKind::velocity;
  std::uint64_t seed = 1;
  double duration_s = 10.0;
};

Trace generate_trace(const GeneratorOptions& options);

// CSV text of a trace, values in shortest round-trip form.
std::string format_trace_csv(const Trace& trace);
// The same, a chunk at a time, so a long trace's text is never held whole.
void write_trace_csv(const Trace& trace, const std::function<void(std::string_view)>& sink);

}  // namespace lever::tool
