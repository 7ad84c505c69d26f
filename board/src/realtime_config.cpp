#include "lever/board/realtime_config.hpp"

#include <sched.h>

#include <charconv>

namespace lever::board {

namespace {

constexpr auto kMinPeriod = std::chrono::microseconds(50);
constexpr auto kMaxPeriod = std::chrono::seconds(1);
// A thread's stack is 8 MiB unless set otherwise; pre-faulting close to that would overflow it.
constexpr std::size_t kMaxPrefault = 4u << 20;

}  // namespace

std::vector<std::string> RealtimeConfig::validate() const {
  std::vector<std::string> problems;
  if (period < kMinPeriod || period > kMaxPeriod) {
    problems.push_back("period: " + std::to_string(period.count()) + " ns, must be within 50 us and 1 s");
  }
  const int max_priority = ::sched_get_priority_max(SCHED_FIFO);
  if (fifo_priority < 0 || fifo_priority > max_priority) {
    problems.push_back("fifo_priority: " + std::to_string(fifo_priority) + ", must be 0 (none) to " +
                       std::to_string(max_priority));
  }
  for (const unsigned cpu : cpus) {
    if (cpu >= CPU_SETSIZE) {
      problems.push_back("cpus: " + std::to_string(cpu) + " is beyond CPU_SETSIZE (" + std::to_string(CPU_SETSIZE) +
                         ")");
    }
  }
  if (prefault_stack_bytes > kMaxPrefault) {
    problems.push_back("prefault_stack_bytes: " + std::to_string(prefault_stack_bytes) + ", at most " +
                       std::to_string(kMaxPrefault) + " (a thread's stack is 8 MiB by default)");
  }
  return problems;
}

std::optional<std::vector<unsigned>> parse_cpu_list(std::string_view text) {
  std::vector<unsigned> cpus;
  const auto number = [](std::string_view s, unsigned& out) {
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    return !s.empty() && ec == std::errc{} && end == s.data() + s.size();
  };
  while (!text.empty()) {
    const std::size_t comma = text.find(',');
    const std::string_view item = text.substr(0, comma);
    text = comma == std::string_view::npos ? std::string_view{} : text.substr(comma + 1);
    if (comma != std::string_view::npos && text.empty()) return std::nullopt;  // a trailing comma
    const std::size_t dash = item.find('-');
    unsigned first = 0, last = 0;
    if (dash == std::string_view::npos) {
      if (!number(item, first)) return std::nullopt;
      last = first;
    } else if (!number(item.substr(0, dash), first) || !number(item.substr(dash + 1), last) || last < first ||
               last >= CPU_SETSIZE) {
      return std::nullopt;
    }
    for (unsigned cpu = first; cpu <= last; ++cpu) cpus.push_back(cpu);
  }
  if (cpus.empty()) return std::nullopt;
  return cpus;
}

}  // namespace lever::board
