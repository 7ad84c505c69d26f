#include "screen_text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>

#include "lever/protocol/fault_names.hpp"

namespace lever::view {
namespace {

using protocol::Role;

std::string value_or_dash(const std::optional<double>& v, const char* format) {
  return v ? fmt::format(fmt::runtime(format), *v) : std::string("-");
}

std::string lever_state(const LeverView& lever) {
  if (!lever.heard) return "unheard";
  if (lever.silent()) return fmt::format("silent {:.1f}s", *lever.heartbeat_age_s);
  return std::string(protocol::name(lever.heartbeat.state));
}

Tone lever_tone(const LeverView& lever) {
  if (!lever.heard || lever.silent()) return Tone::bad;
  switch (lever.heartbeat.state) {
    case protocol::LeverState::armed:
      return Tone::good;
    case protocol::LeverState::fault:
      return Tone::bad;
    default:
      return lever.heartbeat.faults != 0 ? Tone::bad : Tone::warning;
  }
}

// A figure from the lever's status line, marked so: no frame carries it.
std::string from_status(const std::optional<double>& v, const char* format) {
  return v ? fmt::format(fmt::runtime(format), *v) + "*" : std::string("-");
}

void lever_row(std::vector<Line>& out, const PairView& pair, Role role) {
  const LeverView& lever = pair.levers[static_cast<std::size_t>(role)];
  const bool hsi = role == Role::hsi;
  std::string position, velocity, force;
  const auto stale = [](bool is_stale) { return is_stale ? "~" : ""; };
  if (hsi) {
    position = value_or_dash(pair.hsi_position_rad(), "{:+.4f}") + stale(pair.motion_message && pair.motion_stale());
    velocity = value_or_dash(pair.hsi_velocity_rad_s(), "{:+.3f}") + stale(pair.motion_message && pair.motion_stale());
    force = from_status(lever.status ? lever.status->force_n : std::nullopt, "{:+.3f}");
  } else {
    position = from_status(lever.status ? lever.status->position_rad : std::nullopt, "{:+.4f}");
    velocity = from_status(lever.status ? lever.status->velocity_rad_s : std::nullopt, "{:+.3f}");
    force = value_or_dash(pair.top_force_n(), "{:+.3f}") + stale(pair.force_message && pair.force_stale());
  }
  const std::string torque = from_status(lever.status ? lever.status->torque_nm : std::nullopt, "{:+.3f}");
  const std::string homed = !lever.heard ? "-" : lever.heartbeat.position_valid ? "yes" : "no";
  const std::string faults = lever.heard ? protocol::fault_names(lever.heartbeat.faults, ",", "-") : "-";
  out.push_back({fmt::format("  {:<4} {:<11} {:<5} {:>10} {:>10} {:>9} {:>9}  {:>5}/{:<5} {}", hsi ? "HSI" : "TOP",
                             lever_state(lever), homed, position, velocity, force, torque, lever.heartbeats_lost,
                             lever.heartbeats_out_of_order, faults),
                 lever_tone(lever)});
}

// What the direction's sender says it runs, from its settings frame: "deadband p 10.00 % floor 0.020 rad/s
// filter off".
std::string settings_text(const LeverView& sender, const char* unit) {
  if (!sender.settings) return "settings not heard";
  const auto& m = *sender.settings;
  const auto c = protocol::codec_settings(m);
  const std::string filter = m.filter_hz == 0 ? std::string("off") : fmt::format("{:.1f} Hz", c.filter_hz);
  return fmt::format("{} p {:.2f} % floor {:.3f} {} filter {}{}", codec::name(c.mode), 100.0 * c.p, c.floor, unit,
                     filter, m.taring ? "  taring" : "");
}

void direction_row(std::vector<Line>& out, const char* name, const DirectionView& d, const LeverView& sender,
                   const char* unit) {
  const Tone tone = d.lost + d.out_of_order > 0 ? Tone::warning : Tone::normal;
  out.push_back({fmt::format("  {:<14} {:>5.0f}/s {:>6.1f} % of 1 kHz  saves {:>5.1f} %   lost {:<6} late {:<6} "
                             "refresh {:<7} frames {}",
                             name, d.per_second, 100.0 * d.share(), 100.0 * d.savings(), d.lost, d.out_of_order,
                             d.refreshes, d.frames),
                 tone});
  out.push_back({fmt::format("  {:<14} {}", "", settings_text(sender, unit)), Tone::normal});
}

struct SampleRange {
  float lo, hi;
};
// The smallest and largest of the samples from `from` on; none when every one of them is missing.
std::optional<SampleRange> sample_range(const std::vector<std::optional<float>>& samples, std::size_t from) {
  std::optional<SampleRange> range;
  for (std::size_t i = from; i < samples.size(); ++i) {
    if (!samples[i]) continue;
    const float v = *samples[i];
    range = range ? SampleRange{std::min(range->lo, v), std::max(range->hi, v)} : SampleRange{v, v};
  }
  return range;
}

void history_row(std::vector<Line>& out, const char* name, const char* unit,
                 const std::vector<std::optional<float>>& samples, const ScreenOptions& options) {
  constexpr std::size_t kLabel = 18, kRange = 26;
  const std::size_t width = options.width > kLabel + kRange + 10 ? options.width - kLabel - kRange : 10;
  const std::size_t from = samples.size() > width ? samples.size() - width : 0;
  const auto r = sample_range(samples, from);
  const std::string range = r ? fmt::format("{:+.3f} .. {:+.3f} {}", r->lo, r->hi, unit) : std::string("no data");
  const std::vector<std::optional<float>> shown(samples.begin() + static_cast<std::ptrdiff_t>(from), samples.end());
  out.push_back({fmt::format("  {:<16}{} {}", name, sparkline(shown, width, options.utf8), range), Tone::normal});
}

}  // namespace

std::string clip_columns(const std::string& text, std::size_t columns) {
  std::size_t seen = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    // A byte that does not continue a UTF-8 sequence starts a character.
    if ((static_cast<unsigned char>(text[i]) & 0xC0u) != 0x80u) {
      if (seen == columns) return text.substr(0, i);
      ++seen;
    }
  }
  return text;
}

std::string sparkline(const std::vector<std::optional<float>>& samples, std::size_t width, bool utf8) {
  static constexpr std::array<const char*, 8> kBlocks{"\u2581", "\u2582", "\u2583", "\u2584",
                                                      "\u2585", "\u2586", "\u2587", "\u2588"};
  static constexpr std::array<char, 8> kAscii{'_', '.', ',', '-', '~', '=', '^', '#'};
  const std::size_t from = samples.size() > width ? samples.size() - width : 0;
  const auto r = sample_range(samples, from);
  const float lo = r ? r->lo : 0, hi = r ? r->hi : 0;
  std::string out;
  for (std::size_t i = from; i < samples.size(); ++i) {
    if (!samples[i]) {
      out += ' ';
      continue;
    }
    // A flat signal sits in the middle; otherwise its range spans the eight levels.
    std::size_t level = 3;
    if (hi - lo > 1e-6f) {
      const float x = (*samples[i] - lo) / (hi - lo) * 7.0f + 0.5f;
      level = std::min<std::size_t>(7, static_cast<std::size_t>(x));
    }
    if (utf8) {
      out += kBlocks[level];
    } else {
      out += kAscii[level];
    }
  }
  // Padded on the left, so the newest sample is always in the same column.
  const std::size_t shown = samples.size() - from;
  return std::string(width - shown, ' ') + out;
}

std::vector<Line> render(const Snapshot& s, const ReaderState& reader, const ScreenOptions& options) {
  std::vector<Line> out;
  const BusView& bus = s.bus;
  // What must not be cut off by a narrow terminal comes first: the state of the view itself.
  const std::string rate = options.bitrate >= 1e6 ? fmt::format("{:g} Mbit/s", options.bitrate / 1e6)
                                                  : fmt::format("{:g} kbit/s", options.bitrate / 1e3);
  out.push_back({fmt::format("lever-view  {}{}{}  bus load {:.1f} % of {}  {:.0f} frames/s  frames {}  unknown {}  "
                             "rejected {}  kernel drops {}  screen {}/s",
                             reader.interface, reader.link_up ? "" : " (DOWN)", options.frozen ? "  [FROZEN]" : "",
                             100.0 * bus.load, rate, bus.frames_per_s, bus.frames, bus.unknown_ids, bus.rejected,
                             reader.kernel_drops, value_or_dash(options.pictures_per_s, "{:.1f}")),
                 !reader.link_up || reader.kernel_drops > 0 ? Tone::bad : Tone::heading});
  if (s.pairs.empty()) out.push_back({"  no lever frames yet", Tone::warning});
  bool starred = false;
  for (const PairView& pair : s.pairs) {
    out.push_back({"", Tone::normal});
    std::string last = pair.last_command ? fmt::format(", last {}", protocol::name(*pair.last_command)) : "";
    out.push_back({fmt::format("pair {}  (commands seen {}{})", pair.pair, pair.commands, last), Tone::heading});
    out.push_back({fmt::format("  {:<4} {:<11} {:<5} {:>10} {:>10} {:>9} {:>9}  {:>11} {}", "", "state", "homed",
                               "pos rad", "vel rad/s", "force N", "torque Nm", "hb lost/late", "faults"),
                   Tone::heading});
    lever_row(out, pair, Role::hsi);
    lever_row(out, pair, Role::top);
    direction_row(out, "motion HSI>TOP", pair.motion, pair.levers[0], "rad/s");
    direction_row(out, "force  TOP>HSI", pair.force, pair.levers[1], "N");
    history_row(out, "HSI position", "rad", pair.hsi_position_history, options);
    history_row(out, "TOP force", "N", pair.top_force_history, options);
    const bool top_status = pair.levers[1].status.has_value();
    if (top_status) history_row(out, "TOP position*", "rad", pair.top_position_history, options);
    starred = starred || pair.levers[0].status || top_status;
  }
  for (const BridgeView& b : s.bridges) {
    const auto& st = b.status;
    out.push_back(
        {fmt::format("bridge (status input {}): can {}  bus load {}  to network {}/s  from network {}/s  "
                     "gaps {}  reordered {}  latency p99 {} us  ({:.1f} s ago)",
                     b.source + 1, st.can.empty() ? "?" : st.can,
                     st.bus_load ? fmt::format("{:.1f} %", 100.0 * *st.bus_load) : "-",
                     value_or_dash(st.to_network_per_s, "{:.0f}"), value_or_dash(st.from_network_per_s, "{:.0f}"),
                     st.sequence_gaps, st.reordered, value_or_dash(st.latency_p99_us, "{:.0f}"), b.age_s),
         st.sequence_gaps > 0 ? Tone::warning : Tone::normal});
  }
  out.push_back({"", Tone::normal});
  out.push_back(
      {"pos, vel: the HSI's motion frames; force: the TOP's force frames; ~ stale: its sender stopped; "
       "history: one sample per 0.1 s",
       Tone::normal});
  out.push_back(
      {starred ? "* from the lever's status line: no frame carries it" : "-: no frame carries it (--status adds it)",
       Tone::normal});
  out.push_back({"keys: f or space freeze   r reset counters   q quit", Tone::heading});
  return out;
}

}  // namespace lever::view
