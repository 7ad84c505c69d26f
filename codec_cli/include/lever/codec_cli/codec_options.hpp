#pragma once
// The codec's parameters (mode, p, floor, filter_hz), declared once (issue 40): as command-line options for
// lever-codec, lever-ctl set-deadband and lever-hil run and sweep, and as the configuration keys of lever-fw's file.
// A codec::Config field becomes an option in each program and a key in each file by one case here, with the same
// name, range and help everywhere. What legitimately differs between programs (the floor the CAN frame can carry,
// a cut-off checked against a trace's own rate) is a Limits, named at the call.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

#include "lever/codec/config.hpp"
#include "lever/program/numbers.hpp"
#include "lever/protocol/messages.hpp"

namespace lever::program {
class ConfigSchema;
}

namespace lever::codec_cli {

// One per codec::Config field.
enum class Param : std::uint8_t { mode, p, floor, filter_hz };
inline constexpr Param kAllParams[] = {Param::mode, Param::p, Param::floor, Param::filter_hz};

// A set of parameters: "all but the floor" stays true when a parameter is added.
class Params {
 public:
  constexpr Params(std::initializer_list<Param> params) {
    for (const Param p : params) bits_ |= bit(p);
  }
  constexpr bool has(Param p) const { return (bits_ & bit(p)) != 0; }
  constexpr Params without(Param p) const {
    Params rest = *this;
    rest.bits_ &= static_cast<std::uint8_t>(~bit(p));
    return rest;
  }

 private:
  static constexpr std::uint8_t bit(Param p) { return static_cast<std::uint8_t>(1u << static_cast<unsigned>(p)); }
  std::uint8_t bits_ = 0;
};
inline constexpr Params kAll{Param::mode, Param::p, Param::floor, Param::filter_hz};

// Whose options these are: the suffix of their names, who the help says they are for, and the signal's unit.
struct Signal {
  std::string_view suffix;  // "--p" + "-velocity"
  std::string_view scope;   // leads each help text ("HSI->TOP velocity: ..."); empty for a program's one signal
  std::string_view unit;    // the signal's, and so the floor's
};
inline constexpr Signal kBothDirections{"", "both directions", "rad/s or N"};
inline constexpr Signal kVelocity{"-velocity", "HSI->TOP velocity", "rad/s"};
inline constexpr Signal kForce{"-force", "TOP->HSI force", "N"};

// The values a program accepts where programs legitimately differ.
struct Limits {
  double floor_max = program::kUnbounded;
  // 0 is the paper's rule (no floor); a sweep's +floor variant refuses it, as it would not differ from the plain one.
  bool floor_zero = true;
  program::Bounds filter_hz = program::kCutoffAt1kHz;
  // Said after the cut-off's help, where its range cannot say it (a bound known only once a trace is read).
  std::string_view filter_note = {};
  // The help names the steps each value is rounded to in a CAN command frame (lever-ctl sends them).
  bool wire_steps = false;
};
// A Weber fraction's options refuse what a lever refuses (codec::runs_at): an option never sends a command the
// lever drops.
static_assert(program::kWeberFraction.hi == codec::kWeberFractionLimit && program::kWeberFraction.hi_open);

// What a CAN command frame carries (the floor: protocol::kFloorLsb in 16 bits) and the 1 kHz loop can filter.
inline constexpr Limits kOnWire{.floor_max = protocol::kFloorLsb * std::numeric_limits<std::uint16_t>::max()};
// The same, for a program that rounds the values to the frame's steps itself.
inline constexpr Limits kSentOverCan{.floor_max = kOnWire.floor_max, .wire_steps = true};
// A recorded trace at its own rate: any floor, any cut-off above 0 (the trace's Nyquist is checked once it is read).
inline constexpr Limits kOffline{.filter_hz = {0.0, program::kUnbounded, true, false, "a cut-off in Hz"},
                                 .filter_note = "below the trace's Nyquist frequency"};

// "filter_hz": the parameter's name, a configuration file's key in TOML's spelling.
std::string_view key_name(Param param);
// "--filter-hz-velocity": the same name in a command line's spelling, with the signal's suffix.
std::string option_name(Param param, const Signal& signal);

// Adds the options `which` for one signal, bound to config's fields. Each shows its value in config as the default,
// unless the range refuses it: then not giving the option is the only way to have it (lever-codec's cut-off, off).
// `note` ends each help text ("of the +floor variant").
void add_options(CLI::App& app, codec::Config<double>& config, const Signal& signal, const Limits& limits,
                 Params which = kAll, std::string_view note = {});

// Binds every parameter of one signal as a key of `section` ("codec.motion.p"), to config's fields, with the
// options' ranges and help. The section names the signal in a file, so the help does not (no signal.scope).
void bind_keys(program::ConfigSchema& schema, const std::string& section, codec::Config<double>& config,
               const Signal& signal, const Limits& limits);

// One signal's values that override the options without its suffix (--p-velocity over --p): unset unless given.
struct Overrides {
  std::optional<codec::Mode> mode;
  std::optional<double> p, floor, filter_hz;
};
// Adds the options `which` as overrides of base's, whose options add_options declared first; where base has no
// option of its own (lever-hil run has no --floor), the help shows base's value as the default.
void add_overrides(CLI::App& app, Overrides& overrides, const codec::Config<double>& base, const Signal& signal,
                   const Limits& limits, Params which = kAll);
// base with every override given in its place.
codec::Config<double> resolve(const codec::Config<double>& base, const Overrides& overrides);

}  // namespace lever::codec_cli
