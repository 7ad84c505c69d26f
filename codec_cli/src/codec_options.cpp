#include "lever/codec_cli/codec_options.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <string>

#include "lever/program/choices.hpp"
#include "lever/program/config_schema.hpp"

namespace lever::codec_cli {
namespace {

// Each parameter's range, description, field and step below, and its name in key_name: a new codec::Config field
// is one more case in each, and the compiler names every switch that lacks it.

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

// What a parameter is, said once for both syntaxes: an option's help reads "WHAT in UNIT REMARK", a key's
// documentation "UNIT: WHAT REMARK", as the schema prints every key's unit in a place of its own.
struct Description {
  std::string what;
  std::string_view unit;
  std::string remark;
};

Description description(Param param, const Signal& signal, const Limits& limits) {
  switch (param) {
    case Param::mode:
      return {"deadband (zero-order hold) or predictive (linear predictor)", {}, {}};
    case Param::p:
      return {"Weber fraction p, the relative deadband (0.1: 10 %)", {}, {}};
    case Param::floor:
      return {"absolute deadband floor", signal.unit, limits.floor_zero ? " (0: the paper's rule)" : ""};
    case Param::filter_hz:
      return {"low-pass prefilter cut-off", "Hz",
              fmt::format("{}{}", admits(param, 0.0, signal, limits) ? " (0: off)" : " (default: off)",
                          limits.filter_note.empty() ? "" : fmt::format(", {}", limits.filter_note))};
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
  const Description d = description(param, signal, limits);
  std::string text = signal.scope.empty() ? "" : fmt::format("{}: ", signal.scope);
  text += d.what + (d.unit.empty() ? "" : fmt::format(" in {}", d.unit)) + d.remark;
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

std::string_view key_name(Param param) {
  switch (param) {
    case Param::mode:
      return "mode";
    case Param::p:
      return "p";
    case Param::floor:
      return "floor";
    case Param::filter_hz:
      return "filter_hz";
  }
  return "unknown";
}

std::string option_name(Param param, const Signal& signal) {
  std::string name(key_name(param));
  std::replace(name.begin(), name.end(), '_', '-');
  return fmt::format("--{}{}", name, signal.suffix);
}

void bind_keys(program::ConfigSchema& schema, const std::string& section, codec::Config<double>& config,
               const Signal& signal, const Limits& limits) {
  for (const Param param : kAllParams) {
    const std::string key = fmt::format("{}.{}", section, key_name(param));
    const Description d = description(param, signal, limits);
    if (param == Param::mode) {
      schema.choice(key, config.mode, modes(), d.what + d.remark);
      continue;
    }
    std::string what;
    schema.number(key, number_field(config, param), bounds(param, signal, limits, what), std::string(d.unit),
                  d.what + d.remark);
  }
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
