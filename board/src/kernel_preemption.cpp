#include "lever/board/kernel_preemption.hpp"

#include <sys/utsname.h>

#include <fstream>
#include <iterator>
#include <sstream>

namespace lever::board {
namespace {

std::optional<std::string> read_text(const std::string& path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// A whole word of `text`, so that "PREEMPT" is not found in "PREEMPT_DYNAMIC".
bool has_word(std::string_view text, std::string_view word) {
  for (std::size_t at = text.find(word); at != std::string_view::npos; at = text.find(word, at + 1)) {
    const bool starts = at == 0 || text[at - 1] == ' ';
    const std::size_t end = at + word.size();
    const bool ends = end == text.size() || text[end] == ' ' || text[end] == '\n';
    if (starts && ends) return true;
  }
  return false;
}

std::optional<Preemption> mode_named(std::string_view mode) {
  if (mode == "full") return Preemption::full;
  if (mode == "voluntary" || mode == "none") return Preemption::voluntary;
  return std::nullopt;
}

// debugfs lists the modes and brackets the current one in parentheses: "none voluntary (full)".
std::optional<Preemption> debugfs_mode(std::string_view text) {
  const auto open = text.find('(');
  const auto close = text.find(')', open);
  if (open == std::string_view::npos || close == std::string_view::npos) return std::nullopt;
  return mode_named(text.substr(open + 1, close - open - 1));
}

std::optional<Preemption> cmdline_mode(std::string_view cmdline) {
  std::istringstream words{std::string(cmdline)};
  std::optional<Preemption> last;  // the kernel takes the last of repeated parameters
  for (std::string word; words >> word;) {
    if (word.rfind("preempt=", 0) == 0) last = mode_named(std::string_view(word).substr(8));
  }
  return last;
}

std::optional<Preemption> build_default(std::string_view config) {
  if (config.find("\nCONFIG_PREEMPT=y") != std::string_view::npos) return Preemption::full;
  if (config.find("\nCONFIG_PREEMPT_VOLUNTARY=y") != std::string_view::npos ||
      config.find("\nCONFIG_PREEMPT_NONE=y") != std::string_view::npos)
    return Preemption::voluntary;
  return std::nullopt;
}

// The model and the source that named it, decided once for preemption_of() and describe().
struct Verdict {
  Preemption model;
  const char* from;  // "" where no source names it
};

Verdict decide(const KernelPreemptionSources& s) {
  if (s.debugfs_preempt) {
    if (const auto mode = debugfs_mode(*s.debugfs_preempt)) return {*mode, "debugfs sched/preempt"};
  }
  if (has_word(s.uname_version, "PREEMPT_RT")) return {Preemption::realtime, "uname -v"};
  if (has_word(s.uname_version, "PREEMPT_DYNAMIC")) {
    if (!s.cmdline) return {Preemption::unknown, ""};
    if (const auto mode = cmdline_mode(*s.cmdline)) return {*mode, "preempt= on the kernel command line"};
    if (s.build_config) {
      if (const auto mode = build_default("\n" + *s.build_config)) return {*mode, "the build's default, /boot/config"};
    }
    return {Preemption::unknown, ""};
  }
  if (has_word(s.uname_version, "PREEMPT")) return {Preemption::full, "uname -v"};
  return {Preemption::voluntary, "uname -v"};
}

}  // namespace

Preemption preemption_of(const KernelPreemptionSources& s) { return decide(s).model; }

KernelPreemptionSources read_kernel_preemption_sources() {
  KernelPreemptionSources s;
  utsname u{};
  if (::uname(&u) == 0) s.uname_version = u.version;
  s.cmdline = read_text("/proc/cmdline");
  s.debugfs_preempt = read_text("/sys/kernel/debug/sched/preempt");
  s.build_config = read_text(std::string("/boot/config-") + u.release);
  return s;
}

std::string_view name(Preemption p) noexcept {
  switch (p) {
    case Preemption::full:
      return "full";
    case Preemption::realtime:
      return "PREEMPT_RT";
    case Preemption::voluntary:
      return "voluntary";
    case Preemption::unknown:
      return "unknown";
  }
  return "unknown";
}

std::string describe(const KernelPreemptionSources& s) {
  const auto [p, from] = decide(s);
  switch (p) {
    case Preemption::full:
    case Preemption::realtime:
      return "kernel preemption: " + std::string(name(p)) + " (" + std::string(from) + ")";
    case Preemption::voluntary:
      return "warning: the kernel runs the voluntary preemption model (" + std::string(from) +
             "): an ordinary process inside a system call can hold the loop for milliseconds whatever its priority; "
             "boot with preempt=full or a PREEMPT_RT kernel (docs/deploy.md, \"The board's kernel\")";
    case Preemption::unknown:
      break;
  }
  return std::string("kernel preemption: not known (PREEMPT_DYNAMIC; ") +
         (s.cmdline ? "no preempt= on the command line and no readable /boot/config" : "/proc/cmdline not readable") +
         "); the loop needs preempt=full (docs/deploy.md, \"The board's kernel\")";
}

}  // namespace lever::board
