// lever-ctl: operates a lever pair over CAN. It sends a command frame, watches both levers' heartbeats (and for
// tare and set-deadband their settings frames) and resends until each lever the command is for shows the commanded
// state or settings, or refuses it for a reason its heartbeat shows.
#include <fmt/format.h>
#include <poll.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "lever/board/interface_name.hpp"
#include "lever/board/socketcan.hpp"
#include "lever/codec_cli/codec_options.hpp"
#include "lever/program/choices.hpp"
#include "lever/program/numbers.hpp"
#include "lever/program/parse.hpp"
#include "lever/program/text.hpp"
#include "pair_command.hpp"

namespace {

namespace program = lever::program;
namespace protocol = lever::protocol;
using lever::ctl::Judgement;
using lever::ctl::Outcome;
using lever::ctl::Verb;
using Clock = std::chrono::steady_clock;

// A heartbeat comes every 25 ms; a command and its answer cross two bridges in 40-odd ms. 100 ms between
// copies lets one round trip answer before the next copy, and still gives 50 tries within the default timeout.
constexpr auto kResendInterval = std::chrono::milliseconds(100);
// A lever silent this long (ten heartbeats) is judged by no heartbeat at all, not by its last one.
constexpr auto kHeartbeatFresh = std::chrono::milliseconds(250);

struct Options {
  int pair = 0;
  std::string can;
  std::optional<double> timeout_s;
  // set-deadband
  protocol::Direction direction = protocol::Direction::motion;
  lever::codec::Config<double> codec;
};

// One direction, which --direction names.
constexpr lever::codec_cli::Signal kDirection{"", "", "rad/s or N"};

int fail(int code, const std::string& message) {
  fmt::print(stderr, "lever-ctl: {}\n", message);
  return code;
}

struct Lever {
  const char* name;
  protocol::Role role;
  bool target = false;
  std::optional<protocol::HeartbeatMessage> last;
  Clock::time_point heard{};
  std::optional<protocol::SettingsMessage> settings;         // the newest settings frame
  std::optional<protocol::SettingsMessage> settings_before;  // the newest before the first copy went out
  std::optional<protocol::HeartbeatMessage> fresh(Clock::time_point now) const {
    if (last && now - heard <= kHeartbeatFresh) return last;
    return std::nullopt;
  }
  std::string silent_for(Clock::time_point now) const {
    if (!last) return "no heartbeat heard";
    return fmt::format("no heartbeat for {:.1f} s (last: {})", std::chrono::duration<double>(now - heard).count(),
                       lever::ctl::describe(*last));
  }
};

class Session {
 public:
  Session(Verb verb, const Options& o, lever::board::SocketCan can)
      : verb_(verb), options_(o), can_(std::move(can)), command_(command(verb, o)) {
    const auto t = lever::ctl::targets(verb, o.direction);
    levers_[0].target = t.hsi;
    levers_[1].target = t.top;
  }

  int run() {
    const auto start = Clock::now();
    const double timeout_s = options_.timeout_s.value_or(verb_ == Verb::home ? 20.0 : 5.0);
    const auto deadline = start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
    auto next_send = start;
    while (true) {
      const auto now = Clock::now();
      const Judgement j[2] = {judge(levers_[0], now), judge(levers_[1], now)};
      bool all_done = true;
      for (int i = 0; i < 2; ++i) {
        if (!levers_[i].target) continue;
        if (j[i].outcome == Outcome::refused)
          return fail(1, fmt::format("{} pair {}: {} refused: {}", lever::ctl::verb_name(verb_), options_.pair,
                                     levers_[i].name, j[i].why));
        all_done = all_done && j[i].outcome == Outcome::done;
      }
      if (all_done) {
        fmt::print("lever-ctl: {} pair {} on {}: done in {:.3f} s, {} command frame{}{}\n",
                   lever::ctl::verb_name(verb_), options_.pair, can_.interface(),
                   std::chrono::duration<double>(now - start).count(), sent_, sent_ == 1 ? "" : "s", shown());
        return 0;
      }
      if (now >= deadline) return timed_out(j, timeout_s);
      const auto pending = lever::ctl::still_pending({levers_[0].target, levers_[1].target}, j[0], j[1]);
      if (now >= next_send && ready()) {
        // The first copy goes to every target; a resend only to the levers not there yet.
        const bool first = sent_ == 0;
        if (first)
          for (auto& lever : levers_) lever.settings_before = lever.settings;
        if (first || pending.hsi || pending.top) {
          if (const int code = send(first ? levers_[0].target : pending.hsi, first ? levers_[1].target : pending.top);
              code != 0)
            return code;
        }
        next_send = now + kResendInterval;
      }
      const auto wake = std::min(deadline, next_send > now ? next_send : deadline);
      const auto wait_ms = std::chrono::ceil<std::chrono::milliseconds>(wake - Clock::now()).count();
      pollfd fd{can_.fd(), POLLIN, 0};
      if (::poll(&fd, 1, static_cast<int>(std::clamp<long long>(wait_ms, 0, 1000))) < 0 && errno != EINTR)
        return fail(1, fmt::format("poll: {}", std::strerror(errno)));
      if (const int code = drain(); code != 0) return code;
    }
  }

 private:
  static protocol::CommandMessage command(Verb verb, const Options& o) {
    protocol::CommandMessage m;
    m.opcode = lever::ctl::opcode(verb);
    if (verb == Verb::set_deadband) {
      m.direction = o.direction;
      protocol::set_codec_settings(m, o.codec);
    }
    return m;
  }

  // A command confirmed by the settings frame goes out once every target has sent one: its counters from before
  // the command are what a newer one is judged against.
  bool ready() const {
    if (!lever::ctl::confirmed_by_settings(verb_)) return true;
    for (const auto& lever : levers_)
      if (lever.target && !lever.settings) return false;
    return true;
  }

  Judgement judge(const Lever& lever, Clock::time_point now) const {
    const auto heartbeat = lever.fresh(now);
    Judgement j = lever::ctl::judge(verb_, heartbeat);
    if (!heartbeat) j.why = lever.silent_for(now);
    if (!lever::ctl::confirmed_by_settings(verb_) || j.outcome != Outcome::done) return j;
    if (!lever.settings)
      return {Outcome::pending, fmt::format("{}; no settings frame heard (a lever sends one every {} ms)",
                                            lever::ctl::describe(*heartbeat), protocol::kSettingsPeriodMs)};
    if (!lever.settings_before) return {Outcome::pending, "not sent yet"};
    j = lever::ctl::judge_settings(verb_, *lever.settings_before, *lever.settings, command_);
    if (j.outcome != Outcome::done)
      j.why = fmt::format("its settings frame says {}: {}", lever::ctl::describe(*lever.settings, lever.role), j.why);
    return j;
  }

  std::string shown() const {
    std::string out;
    for (const auto& lever : levers_) {
      if (!lever.target || !lever.last) continue;
      out += fmt::format("{}{}: {}", out.empty() ? " (" : "; ", lever.name, lever::ctl::describe(*lever.last));
      if (lever::ctl::confirmed_by_settings(verb_) && lever.settings)
        out += fmt::format("; {}", lever::ctl::describe(*lever.settings, lever.role));
    }
    return out.empty() ? out : out + ")";
  }

  int timed_out(const Judgement (&j)[2], double timeout_s) const {
    std::string why;
    for (int i = 0; i < 2; ++i)
      if (levers_[i].target && j[i].outcome != Outcome::done)
        why += fmt::format("{}{}: {}", why.empty() ? "" : "; ", levers_[i].name, j[i].why);
    return fail(1,
                fmt::format("{} pair {}: not done within {} s ({} command frame{}): {}", lever::ctl::verb_name(verb_),
                            options_.pair, program::short_number(timeout_s), sent_, sent_ == 1 ? "" : "s", why));
  }

  int send(bool to_hsi, bool to_top) {
    protocol::CommandMessage m = command_;
    m.to_hsi = to_hsi;
    m.to_top = to_top;
    switch (can_.write(protocol::pack(m, static_cast<std::uint8_t>(options_.pair)))) {
      case lever::board::IoStatus::ok:
        ++sent_;
        return 0;
      case lever::board::IoStatus::would_block:  // the interface's queue is full: the next copy tries again
        return 0;
      case lever::board::IoStatus::interface_down:
        return fail(1, fmt::format("{} is down", can_.interface()));
      case lever::board::IoStatus::interface_gone:
        return fail(1, fmt::format("{} is gone", can_.interface()));
      default:
        return fail(1, fmt::format("sending on {}: {}", can_.interface(), std::strerror(can_.last_errno())));
    }
  }

  int drain() {
    protocol::CanFrame frame;
    std::int64_t timestamp_us = 0;
    while (true) {
      switch (can_.read(frame, timestamp_us)) {
        case lever::board::IoStatus::ok:
          take(frame);
          continue;
        case lever::board::IoStatus::would_block:
          return 0;
        case lever::board::IoStatus::skipped:
        case lever::board::IoStatus::error_frame:
          continue;
        case lever::board::IoStatus::interface_down:
          return fail(1, fmt::format("{} is down", can_.interface()));
        case lever::board::IoStatus::interface_gone:
          return fail(1, fmt::format("{} is gone", can_.interface()));
        case lever::board::IoStatus::error:
          return fail(1, fmt::format("reading {}: {}", can_.interface(), std::strerror(can_.last_errno())));
      }
    }
  }

  // A frame that does not decode is not a heartbeat or settings frame of this pair's levers, whatever its id says.
  void take(const protocol::CanFrame& frame) {
    protocol::FrameAddress address;
    if (protocol::classify(frame.id, address) != protocol::DecodeError::none || address.pair != options_.pair) return;
    auto& lever = levers_[address.role == protocol::Role::hsi ? 0 : 1];
    if (address.kind == protocol::MessageKind::heartbeat) {
      protocol::HeartbeatMessage m;
      if (protocol::decode(frame, m, address) != protocol::DecodeError::none) return;
      lever.last = m;
      lever.heard = Clock::now();
    } else if (address.kind == protocol::MessageKind::settings) {
      protocol::SettingsMessage m;
      if (protocol::decode(frame, m, address) != protocol::DecodeError::none) return;
      lever.settings = m;
    }
  }

  Verb verb_;
  Options options_;
  lever::board::SocketCan can_;
  protocol::CommandMessage command_;
  Lever levers_[2] = {{"HSI", protocol::Role::hsi, false, std::nullopt, {}, std::nullopt, std::nullopt},
                      {"TOP", protocol::Role::top, false, std::nullopt, {}, std::nullopt, std::nullopt}};
  int sent_ = 0;
};

void add_common(CLI::App* sub, Options& o) {
  sub->add_option("--pair", o.pair, "the lever pair, 0-15 (its number in every CAN id)")
      ->required()
      ->check(program::whole(0, 15));
  sub->add_option("--can", o.can, "the SocketCAN interface the pair's levers (or a bridge to them) are on")->required();
  sub->add_option("--timeout", o.timeout_s,
                  "seconds to wait for both levers to show the commanded state (default 5; home 20, a homing "
                  "takes up to 15)")
      ->check(program::number({0.0, 3600.0, true, false, "a duration in seconds"}));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Operates a lever pair over CAN: sends a command frame to the pair, watches both levers' heartbeats and\n"
      "resends it every 100 ms until each lever shows the commanded state (armed; disarmed; homed: position\n"
      "valid), or refuses it for a reason its heartbeat shows (a state or a latched fault the command cannot get\n"
      "past). Commands are idempotent on the levers, so a resend is harmless (docs/can-protocol.md). Tare and\n"
      "set-deadband are confirmed by the lever's settings frame instead: sent once the lever's settings frame is\n"
      "heard, resent until a newer one shows the commanded values (set-deadband: mode, p, floor, filter; its\n"
      "count of changes moved on) or a finished tare (its count of tares moved on)."};
  program::describe(app, "lever-ctl");
  app.footer(
      "Exit status: 0 done (every lever the command is for shows the commanded state, or settings, or a finished\n"
      "tare); 1 a lever refused or did not show it within the timeout (which, and why from its heartbeat or\n"
      "settings frame), or the CAN interface failed; 2 bad input (an option, an interface that does not exist).");
  Options o;
  // Each command with what it does; its name is the protocol's (protocol::name of its opcode).
  const std::pair<Verb, const char*> verbs[] = {
      {Verb::arm, "arm both levers (each must be homed, with no fault latched)"},
      {Verb::disarm, "disarm both levers (ends a fault's safe behaviour; the faults stay latched)"},
      {Verb::rearm, "re-arm both levers: clears latched faults whose conditions are gone, and arms"},
      {Verb::home, "home both levers (the ones already homed stay as they are)"},
      {Verb::tare, "tare the TOP's strain gauge (the lever disarmed and untouched)"},
      {Verb::set_deadband, "set one direction's deadband at its sending end (motion: the HSI, force: the TOP)"}};
  std::vector<std::pair<CLI::App*, Verb>> subs;
  CLI::App* deadband = nullptr;
  for (const auto& [verb, what] : verbs) {
    CLI::App* sub = app.add_subcommand(std::string(lever::ctl::verb_name(verb)), what);
    add_common(sub, o);
    subs.emplace_back(sub, verb);
    if (verb == Verb::set_deadband) deadband = sub;
  }
  const program::Choices<protocol::Direction> directions{{"motion", protocol::Direction::motion},
                                                         {"force", protocol::Direction::force}};
  deadband->add_option("--direction", o.direction, "motion (HSI to TOP) or force (TOP to HSI)")
      ->required()
      ->transform(program::one_of(directions));
  lever::codec_cli::add_options(*deadband, o.codec, kDirection, lever::codec_cli::kSentOverCan);
  // Required, unlike in the other programs: set-deadband changes a running lever, and sends no p it was not given.
  deadband->get_option("--p")->required()->default_str("");
  app.require_subcommand(1);

  if (const auto stop = program::parse(app, argc, argv)) return *stop;
  Verb verb = Verb::arm;
  for (const auto& [sub, v] : subs)
    if (sub->parsed()) verb = v;
  if (const auto problem = lever::board::interface_name_problem(o.can))
    return fail(2, fmt::format("--can '{}': {}", program::printable(o.can), *problem));

  lever::board::SocketCanConfig config;
  config.interface = o.can;
  config.timestamps = false;
  for (const auto role : {protocol::Role::hsi, protocol::Role::top}) {
    config.filters.push_back({protocol::heartbeat_id(static_cast<std::uint8_t>(o.pair), role), 0x7FF});
    config.filters.push_back({protocol::settings_id(static_cast<std::uint8_t>(o.pair), role), 0x7FF});
  }
  auto can = lever::board::SocketCan::open(config);
  if (!can) return fail(can.error().errno_value == ENODEV ? 2 : 1, can.error().message);
  return Session(verb, o, std::move(can).value()).run();
}
