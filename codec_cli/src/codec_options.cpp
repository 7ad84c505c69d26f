#include "lever/codec_cli/codec_options.hpp"

#include <fmt/format.h>

#include <string>

#include "lever/program/choices.hpp"

namespace lever::codec_cli {
namespace {

// Each parameter's name, range, help, field and step below: a new codec::Config field is one more case in each,
// and the compiler names every switch that lacks it.
std::string_view base_name(Param param) {
  switch (param) {
    case Param::mode:
      return "mode";
    case Param::p:
      return "p";
    case Param::floor:
      return "floor";
    case Param::filter_hz:
      return "filter-hz";
  }
  return "unknown";
}

// A number parameter's range; `what` keeps the text the floor's range is named by (it names the signal's unit).
program::Bounds bounds(Param param, const Signal& signal, const Limits& limits, std::string& what) {
  switch (param) {
    case Param::p:
      return program::kWeberFraction;
    case Param::floor:
      what = fmt::format("a floor in {}", signal.unit);
      return {0.0, limits.floor_max, !limits.floor_zero, false, what};
    case Param::filter_hz:
      return limits.filter_hz;
    case Param::mode:
      break;
  }
  return {};
}

bool admits(Param param, double value, const Signal& signal, const Limits& limits) {
  std::string what;
  return !program::check_number(value, bounds(param, signal, limits, what));
}

std::string what_it_is(Param param, const Signal& signal, const Limits& limits) {
  switch (param) {
    case Param::mode:
      return "deadband (zero-order hold) or predictive (linear predictor)";
    case Param::p:
      return "Weber fraction p, the relative deadband (0.1: 10 %)";
    case Param::floor:
      return fmt::format("absolute deadband floor in {}{}", signal.unit,
                         limits.floor_zero ? " (0: the paper's rule)" : "");
    case Param::filter_hz:
      return fmt::format("low-pass prefilter cut-off in Hz{}{}",
                         admits(param, 0.0, signal, limits) ? " (0: off)" : " (default: off)",
                         limits.filter_note.empty() ? "" : fmt::format(", {}", limits.filter_note));
  }
  return {};
}

// The step a CAN command frame carries the value in (protocol's set_deadband fields); 0 for none.
double wire_step(Param param) {
  switch (param) {
    case Param::p:
      return protocol::kPLsb;
    case Param::floor:
      return protocol::kFloorLsb;
    case Param::filter_hz:
      return protocol::kFilterHzLsb;
    case Param::mode:
      break;
  }
  return 0.0;
}

template <typename Config>  // codec::Config<double> or Overrides, whose numbers are optional
auto& number_field(Config& config, Param param) {
  switch (param) {
    case Param::p:
      return config.p;
    case Param::floor:
      return config.floor;
    case Param::filter_hz:
    case Param::mode:  // never asked: the mode is no number
      break;
  }
  return config.filter_hz;
}

std::string help(Param param, const Signal& signal, const Limits& limits) {
  std::string text = signal.scope.empty() ? "" : fmt::format("{}: ", signal.scope);
  text += what_it_is(param, signal, limits);
  if (limits.wire_steps && wire_step(param) > 0.0)
    text += fmt::format(", sent in steps of {}", program::short_number(wire_step(param)));
  return text;
}

const program::Choices<codec::Mode>& modes() {
  static const auto choices = program::choices_of(codec::kAllModes, codec::name);
  return choices;
}

template <typename Config>
CLI::Option* declare(CLI::App& app, Param param, Config& target, const Signal& signal, const Limits& limits,
                     const std::string& text) {
  const std::string name = option_name(param, signal);
  if (param == Param::mode) return app.add_option(name, target.mode, text)->transform(program::one_of(modes()));
  std::string what;
  return app.add_option(name, number_field(target, param), text)
      ->check(program::number(bounds(param, signal, limits, what)));
}

// The value as help shows it; empty (none shown) when the range refuses it, so that only leaving it out gives it.
std::string shown_default(Param param, const codec::Config<double>& config, const Signal& signal,
                          const Limits& limits) {
  if (param == Param::mode) return std::string(codec::name(config.mode));
  const double value = number_field(config, param);
  return admits(param, value, signal, limits) ? program::short_number(value) : "";
}

}  // namespace

std::string option_name(Param param, const Signal& signal) {
  return fmt::format("--{}{}", base_name(param), signal.suffix);
}

void add_options(CLI::App& app, codec::Config<double>& config, const Signal& signal, const Limits& limits, Params which,
                 std::string_view note) {
  for (const Param param : kAllParams) {
    if (!which.has(param)) continue;
    const std::string text = help(param, signal, limits) + (note.empty() ? "" : fmt::format(", {}", note));
    declare(app, param, config, signal, limits, text)->default_str(shown_default(param, config, signal, limits));
  }
}

void add_overrides(CLI::App& app, Overrides& overrides, const codec::Config<double>& base, const Signal& signal,
                   const Limits& limits, Params which) {
  for (const Param param : kAllParams) {
    if (!which.has(param)) continue;
    const std::string overridden = option_name(param, Signal{});
    const bool has_base = app.get_option_no_throw(overridden) != nullptr;
    const std::string text = help(param, signal, limits) + (has_base ? fmt::format("; overrides {}", overridden) : "");
    CLI::Option* option = declare(app, param, overrides, signal, limits, text);
    if (!has_base) option->default_str(shown_default(param, base, signal, limits));
  }
}

codec::Config<double> resolve(const codec::Config<double>& base, const Overrides& overrides) {
  return {overrides.mode.value_or(base.mode), overrides.p.value_or(base.p), overrides.floor.value_or(base.floor),
          overrides.filter_hz.value_or(base.filter_hz)};
}

}  // namespace lever::codec_cli
