#include "lever/hil/fault_spec.hpp"

#include <charconv>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace lever::hil {
namespace {

constexpr std::pair<std::string_view, FaultKind> kKinds[] = {
    {"link-down", FaultKind::link_down},
    {"burst-loss", FaultKind::burst_loss},
    {"delay-step", FaultKind::delay_step},
    {"bus-off", FaultKind::bus_off},
    {"encoder-glitch", FaultKind::encoder_glitch},
    {"gauge-stale", FaultKind::gauge_stale},
    {"gauge-saturated", FaultKind::gauge_saturated},
    {"motor-fault", FaultKind::motor_fault},
    {"tick-late", FaultKind::tick_late},
    {"reboot", FaultKind::reboot},
};

// The spec as echoed in a message: a 100 kB argument is not repeated whole (control bytes are escaped by the
// program that prints the message).
std::string shown(std::string_view s) { return s.size() <= 40 ? std::string(s) : std::string(s.substr(0, 40)) + "..."; }

double number(std::string_view s, std::string_view what, std::string_view spec) {
  double v = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v) || v < 0)
    throw std::invalid_argument("fault '" + shown(spec) + "': " + std::string(what) + " '" + shown(s) +
                                "' is not a non-negative number");
  return v;
}

}  // namespace

std::string_view to_string(FaultKind kind) {
  for (const auto& [name, k] : kKinds)
    if (k == kind) return name;
  return "?";
}

FaultSpec parse_fault_spec(std::string_view text) {
  FaultSpec f;
  f.text = std::string(text);
  const auto at = text.find('@');
  if (at == std::string_view::npos)
    throw std::invalid_argument("fault '" + shown(f.text) + "': expected KIND@START[+DURATION][:ARG]");
  const auto kind = text.substr(0, at);
  bool known = false;
  for (const auto& [name, k] : kKinds)
    if (name == kind) {
      f.kind = k;
      known = true;
    }
  if (!known) {
    std::string names;
    for (const auto& [name, k] : kKinds) names += (names.empty() ? "" : ", ") + std::string(name);
    throw std::invalid_argument("fault '" + shown(f.text) + "': unknown kind '" + shown(kind) + "' (one of " + names +
                                ")");
  }
  auto rest = text.substr(at + 1);
  std::string_view arg;
  if (const auto colon = rest.find(':'); colon != std::string_view::npos) {
    arg = rest.substr(colon + 1);
    rest = rest.substr(0, colon);
  }
  bool has_duration = false;
  if (const auto plus = rest.find('+'); plus != std::string_view::npos) {
    f.duration_s = number(rest.substr(plus + 1), "duration", text);
    rest = rest.substr(0, plus);
    has_duration = true;
  }
  f.start_s = number(rest, "start", text);
  if (f.kind == FaultKind::delay_step) {
    if (arg.empty()) throw std::invalid_argument("fault '" + shown(f.text) + "': delay-step needs :MILLISECONDS");
    f.value = number(arg, "delay", text);
    // The network model queues datagrams for the delay: a minute is already more than any watchdog allows.
    if (f.value > 60000.0)
      throw std::invalid_argument("fault '" + shown(f.text) + "': delay '" + shown(arg) + "' ms is over 60000");
    if (!has_duration) f.duration_s = std::numeric_limits<double>::infinity();
  } else if (!arg.empty() && (f.kind == FaultKind::link_down || f.kind == FaultKind::burst_loss)) {
    // The link joins both sites: a site given here would be ignored, and the user would believe it was not.
    throw std::invalid_argument("fault '" + shown(f.text) + "': " + std::string(to_string(f.kind)) +
                                " affects the link between both sites and takes no ':" + shown(arg) + "'");
  } else if (!arg.empty()) {
    if (arg == "hsi") {
      f.site = Site::hsi;
    } else if (arg == "top") {
      f.site = Site::top;
    } else {
      throw std::invalid_argument("fault '" + shown(f.text) + "': ':" + shown(arg) + "' is not hsi or top");
    }
  }
  if (f.kind == FaultKind::reboot && !has_duration) f.duration_s = 0.0;  // back at once: the hardest case
  return f;
}

}  // namespace lever::hil
