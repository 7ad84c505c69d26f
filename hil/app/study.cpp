#include "study.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "cli_choices.hpp"
#include "lever/hil/hosted_rig.hpp"
#include "lever/program/numbers.hpp"
#include "lever/program/output_file.hpp"
#include "lever/program/parse.hpp"
#include "lever/program/text.hpp"
#include "lever/study/observer.hpp"
#include "lever/study/pair_watch.hpp"
#include "lever/study/session_log.hpp"
#include "report.hpp"

namespace lever::hil {
namespace {

using protocol::Direction;
using protocol::Role;
using Clock = std::chrono::steady_clock;

constexpr Direction kDirections[] = {Direction::motion, Direction::force};
constexpr Nanos kMs = 1'000'000;
// As lever-study's runner: a copy of an unconfirmed command every 200 ms (a frame lost on a bus).
constexpr Nanos kResendEvery = 200 * kMs;
// The host console re-arms a faulted lever within a few 100 ms periods; a pair not ready for this long never will be.
constexpr Nanos kReadyLimit = 30'000 * kMs;

// The HIL's pair as lever-study's runner sees a pair: every frame the host's node receives goes into a PairWatch
// with its time on the bus, and the bus's clock is the newest frame's time, as the kernel's receive times are.
class SimulatedPair {
 public:
  explicit SimulatedPair(const SimConfig& config) : rig_(config), watch_(config.hsi_firmware.pair) {}

  void power_up() {
    rig_.power_up();
    drain();
  }
  void tick() {
    rig_.step();
    drain();
  }
  // A command frame from the host; a full transmit queue is a lost frame, which the confirmation's copy covers.
  void send(const protocol::CommandMessage& m) { (void)rig_.send(protocol::pack(m, rig_.config().hsi_firmware.pair)); }
  const study::PairWatch& watch() const { return watch_; }
  std::int64_t bus_us() const { return watch_.newest_us(); }
  Nanos now() const { return rig_.now(); }

 private:
  void drain() {
    TimedFrame f;
    while (rig_.receive(f)) watch_.on_frame(f.frame, f.time / 1000);
  }

  HostedRig rig_;
  study::PairWatch watch_;
};

// A line on stderr once a session has taken a second of wall time, so a long one shows it is alive.
class Progress {
 public:
  void update(int attempt, double simulated_s) {
    const auto now = Clock::now();
    if (now - start_ < std::chrono::seconds(1) || now - last_ < std::chrono::seconds(2)) return;
    last_ = now;
    shown_ = true;
    const double wall = std::chrono::duration<double>(now - start_).count();
    fmt::print(stderr, "{}lever-hil study: trial {}, {:.0f} s simulated in {:.0f} s{}", tty_ ? "\r" : "", attempt,
               simulated_s, wall, tty_ ? "" : "\n");
  }
  double wall_s() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }
  ~Progress() {
    if (shown_ && tty_) fmt::print(stderr, "\n");
  }

 private:
  bool tty_ = ::isatty(STDERR_FILENO) == 1;
  bool shown_ = false;
  Clock::time_point start_ = Clock::now(), last_{};
};

SimConfig hil_config(const StudyOptions& o) {
  SimConfig c;
  c.scenario = ScenarioKind::wall_tap;
  c.seed = o.seed;
  c.topology = o.topology;
  c.gauge_chain = o.gauge_chain;
  set_hsi_force_loop(c, o.hsi_force_loop);
  // The levers start as the paper's plain intervals run: the deadband at p = 0 on both paths. Every interval asks
  // for its own p; the mode, floor and prefilter stay these (lever-study's runner keeps the pair's own).
  c.velocity_codec = {codec::Mode::deadband, 0.0, 0.0, 0.0};
  c.force_codec = {codec::Mode::deadband, 0.0, 0.0, 0.0};
  return c;
}

std::string gauge_chain_name(const SimConfig& c) {
  return std::string(name(reads_paper_gauge(c) ? GaugeChain::paper_adc : GaugeChain::dad141));
}

// What the header says of the simulated pair: enough to run the same session again, and the clock its bus times
// are on.
nlohmann::json simulator_json(const StudyOptions& o, const SimConfig& c) {
  nlohmann::json observer = o.protocol == "3ifc" ? nlohmann::json{{"model", "weibull"},
                                                                  {"threshold", o.threshold},
                                                                  {"slope", o.slope},
                                                                  {"lapse", o.lapse},
                                                                  {"guess", 1.0 / 3.0}}
                                                 : nlohmann::json{{"model", "linear"},
                                                                  {"p1_velocity", study::RatingObserver{}.p1_velocity},
                                                                  {"p1_force", study::RatingObserver{}.p1_force},
                                                                  {"sigma", study::RatingObserver{}.sigma}};
  return {{"program", "lever-hil study"},
          {"scenario", name(ScenarioKind::wall_tap)},
          {"topology", name(c.topology)},
          {"gauge_chain", gauge_chain_name(c)},
          {"hsi_force_loop", o.hsi_force_loop},
          {"seed", c.seed},
          {"clock", "simulated: bus times are microseconds of the HIL's clock from the levers' power-up"},
          {"observer", observer}};
}

class Session {
 public:
  Session(const StudyOptions& o, SimulatedPair& pair, double open_interval_s)
      : o_(o), pair_(pair), open_interval_s_(open_interval_s) {}

  // Each lever's settings as it powered up: the mode, floor and prefilter every interval keeps.
  void learn_baseline() {
    wait_until([&] { return both_settings_seen(); }, "no settings frame from both levers");
    for (const auto d : kDirections) baseline_[index(d)] = *pair_.watch().lever(study::sender_of(d)).settings;
  }

  // Presents the trial on the pair; `void_reason` set when the pair spoilt it, as lever-study's runner voids one.
  void present(const study::Trial& trial, study::TrialRecord& record, std::optional<std::string>& void_reason) {
    const auto count = trial.intervals.size();
    for (std::size_t i = 0; i < count; ++i) {
      auto& interval_record = record.intervals[i];
      const study::Interval& interval = trial.intervals[i];
      if (i == 0) {
        wait_until([&] { return pair_.watch().not_ready(pair_.bus_us()).empty(); }, "the pair was not ready");
      } else if (const auto why = pair_.watch().not_ready(pair_.bus_us()); !why.empty()) {
        void_reason = fmt::format("before interval {}: {}", i + 1, why);
        return;
      }
      nlohmann::json confirmed = nlohmann::json::object();
      apply(interval, confirmed, void_reason);
      if (void_reason) return;
      interval_record.confirmed = confirmed;
      const std::array<std::uint64_t, 2> frames_before{pair_.watch().data_frames(Direction::motion),
                                                       pair_.watch().data_frames(Direction::force)};
      const std::int64_t start_us = pair_.bus_us();
      interval_record.start_bus_us = start_us;
      // Familiarization and the briefing have no length of their own (a person ends them): the simulated subject
      // takes one interval's length.
      const double length_s = interval.duration_s > 0.0 ? interval.duration_s : open_interval_s_;
      const std::int64_t end_us = start_us + static_cast<std::int64_t>(length_s * 1e6);
      const Nanos silent_after = pair_.now() + static_cast<Nanos>((length_s + 1.0) * 1e9);
      while (pair_.bus_us() < end_us) {
        if (pair_.now() >= silent_after) {
          void_reason = fmt::format("interval {}: the bus went silent", i + 1);
          break;
        }
        pair_.tick();
        if (const auto why = spoiled(); !why.empty()) {
          void_reason = fmt::format("interval {}: {}", i + 1, why);
          break;
        }
      }
      interval_record.end_bus_us = pair_.bus_us();
      interval_record.frames_velocity = pair_.watch().data_frames(Direction::motion) - frames_before[0];
      interval_record.frames_force = pair_.watch().data_frames(Direction::force) - frames_before[1];
      if (void_reason) return;
      if (i + 1 < count) run_for(trial.gap_s);
    }
  }

 private:
  static std::size_t index(Direction d) { return static_cast<std::size_t>(d); }

  bool both_settings_seen() const {
    for (const auto d : kDirections)
      if (!pair_.watch().lever(study::sender_of(d)).settings) return false;
    return true;
  }

  template <typename Done>
  void wait_until(Done&& done, const char* what) {
    const Nanos limit = pair_.now() + kReadyLimit;
    while (!done()) {
      if (pair_.now() >= limit) {
        const auto why = pair_.watch().not_ready(pair_.bus_us());
        throw std::runtime_error(fmt::format("the HIL's pair: {} within {} s of simulated time{}", what,
                                             kReadyLimit / 1'000'000'000, why.empty() ? "" : ": " + why));
      }
      pair_.tick();
    }
  }

  void run_for(double seconds) {
    const Nanos until = pair_.now() + static_cast<Nanos>(seconds * 1e9);
    while (pair_.now() < until) pair_.tick();
  }

  // As lever-study's runner: the command to the path's sending lever, a copy every 200 ms, until its settings frame
  // shows the counter moved on and the values asked for; false after the confirmation timeout.
  bool confirm(Direction d, const protocol::SettingsMessage& wanted) {
    const auto& seen = pair_.watch().lever(study::sender_of(d));
    const std::uint8_t before = seen.settings ? seen.settings->changes : 0;
    const Nanos deadline = pair_.now() + static_cast<Nanos>(o_.confirm_timeout_s * 1e9);
    Nanos next_copy = pair_.now();
    while (!(seen.settings && study::confirms(*seen.settings, before, wanted))) {
      if (pair_.now() >= deadline) return false;
      if (pair_.now() >= next_copy) {
        pair_.send(study::command_for(d, wanted));
        next_copy = pair_.now() + kResendEvery;
      }
      pair_.tick();
    }
    return true;
  }

  // The interval's settings on both levers, each as the lever's own settings frame shows it.
  void apply(const study::Interval& interval, nlohmann::json& confirmed, std::optional<std::string>& why) {
    for (const auto d : kDirections) {
      const Role role = study::sender_of(d);
      const auto wanted = study::settings_for(interval, d, baseline_[index(d)]);
      const auto& seen = pair_.watch().lever(role);
      if (!confirm(d, wanted)) {
        why = fmt::format("the {} did not confirm {} within {} s (its settings frame: {})", study::role_name(role),
                          study::describe(wanted), o_.confirm_timeout_s,
                          seen.settings ? study::describe(*seen.settings) : std::string("none"));
        return;
      }
      confirmed[role == Role::hsi ? "hsi" : "top"] = study::settings_json(*seen.settings, seen.settings_us);
      confirmed_[static_cast<std::size_t>(role)] = *seen.settings;
    }
  }

  std::string spoiled() const {
    auto why = pair_.watch().not_ready(pair_.bus_us());
    if (!why.empty()) return why;
    for (const auto role : {Role::hsi, Role::top}) {
      const auto& seen = pair_.watch().lever(role);
      if (seen.settings && !protocol::same_codec_settings(*seen.settings, confirmed_[static_cast<std::size_t>(role)]))
        return fmt::format("the {}'s settings changed to {}", study::role_name(role), study::describe(*seen.settings));
    }
    return {};
  }

  const StudyOptions& o_;
  SimulatedPair& pair_;
  double open_interval_s_;
  std::array<protocol::SettingsMessage, 2> baseline_{};   // by direction
  std::array<protocol::SettingsMessage, 2> confirmed_{};  // by role
};

// The procedure's configuration from the options: the protocol's own defaults, the paper's, unless given.
nlohmann::json procedure_config(const StudyOptions& o) {
  study::ThreeIfcConfig three_ifc = o.three_ifc;
  study::RatingConfig rating = o.rating;
  if (o.interval_s) three_ifc.interval_s = rating.interval_s = *o.interval_s;
  // A combination out of range (start_p above max_p), in the procedure's own terms, before anything runs.
  if (o.protocol == "3ifc") {
    study::check(three_ifc);
    return study::to_json(three_ifc);
  }
  study::check(rating);
  return study::to_json(rating);
}

study::SessionHeader header_of(const StudyOptions& o, const SimConfig& c) {
  study::SessionHeader h;
  h.protocol = o.protocol;
  h.subject = o.subject;
  h.seed = o.seed;
  h.simulated = true;
  h.config = procedure_config(o);
  h.simulator = simulator_json(o, c);
  return h;
}

}  // namespace

void add_study_options(CLI::App& cmd, StudyOptions& o) {
  cmd.add_option("--log", o.log, "the session log to write (JSON Lines; refused if it exists)")
      ->required()
      ->check(program::path());
  cmd.add_option("--protocol", o.protocol, "3ifc or rating")
      ->check(CLI::IsMember({"3ifc", "rating"}))
      ->default_str("3ifc");
  cmd.add_option("--subject", o.subject, "the simulated subject's name in the log")->default_str("sim");
  cmd.add_option("--seed", o.seed, "the seed of the procedure, the observer and the HIL (power-up, operator, noise)")
      ->check(program::seed())
      ->default_str("1");
  cmd.add_option("--interval-s", o.interval_s, "an interval's length (paper: 20 s for 3ifc, 30 s for rating)")
      ->check(program::number({0.1, 600.0, false, false, "a time in seconds"}));
  o.three_ifc_only.push_back(
      cmd.add_option("--gap-s", o.three_ifc.gap_s, "3ifc: the pause between a trial's intervals (our reading: 1)")
          ->check(program::number({0.0, 60.0, false, false, "a time in seconds"}))
          ->default_str("1"));
  o.three_ifc_only.push_back(
      cmd.add_option("--start-p", o.three_ifc.start_p, "3ifc: p of a pass's first trial (paper: 0.025)")
          ->check(program::number(program::kWeberFraction)));
  o.three_ifc_only.push_back(
      cmd.add_option("--step", o.three_ifc.step, "3ifc: the rise of p after a wrong answer (our reading: 0.025)")
          ->check(program::number({0.0, 1.0, true, true, "a fraction"})));
  o.three_ifc_only.push_back(cmd.add_option("--max-p", o.three_ifc.max_p, "3ifc: the largest p (paper: 0.25)")
                                 ->check(program::number({0.0, 1.0, true, true, "a fraction"})));
  o.three_ifc_only.push_back(cmd.add_option("--right-in-a-row", o.three_ifc.right_in_a_row,
                                            "3ifc: right answers in a row that end a pass (paper: 3)")
                                 ->check(program::whole(1, 100)));
  o.three_ifc_only.push_back(
      cmd.add_option("--threshold", o.threshold, "3ifc: the observer's threshold (Weibull alpha)")
          ->check(program::number({0.0, 1.0, true, true, "a fraction"}))
          ->default_str("0.12"));
  o.three_ifc_only.push_back(cmd.add_option("--slope", o.slope, "3ifc: the Weibull slope beta")
                                 ->check(program::number({0.0, 100.0, true, false, "a slope"}))
                                 ->default_str("3"));
  o.three_ifc_only.push_back(cmd.add_option("--lapse", o.lapse, "3ifc: the lapse rate lambda")
                                 ->check(program::number({0.0, 0.5, false, true, "a rate"}))
                                 ->default_str("0.02"));
  cmd.add_option("--topology", o.topology, "one-controller (the paper's PC), one-site or two-sites")
      ->transform(program::one_of(kTopologies))
      ->default_str(std::string(name(Topology::one_controller)));
  cmd.add_option("--gauge-chain", o.gauge_chain,
                 "the strain-gauge chain: dad141 (Fig. 8's setup), paper-adc (an assumed chain for the paper's PC) or "
                 "topology (the topology's own)")
      ->transform(program::one_of(kGaugeChains))
      ->default_str("dad141");
  cmd.add_option("--hsi-force-loop", o.hsi_force_loop,
                 "the HSI's force loop on its own gauge: on or off (refused on paper-adc, where it makes the contact "
                 "chatter)")
      ->transform(program::one_of(kOnOff))
      ->default_str("on");
  cmd.add_option("--confirm-timeout", o.confirm_timeout_s,
                 "simulated seconds for a lever to show an interval's settings (then the trial is void)")
      ->check(program::number({0.05, 60.0, false, false, "a time in seconds"}))
      ->default_str("1");
}

int run_study(const StudyOptions& o) {
  if (o.log == "-") throw std::invalid_argument("--log must name a file, not stdout: lever-study report reads it back");
  if (std::filesystem::exists(std::filesystem::symlink_status(o.log)))
    throw std::invalid_argument(
        fmt::format("--log {} exists: a session log is never written over", program::printable(o.log)));
  if (o.protocol == "rating")
    for (const auto* option : o.three_ifc_only)
      if (option->count() > 0)
        throw std::invalid_argument(
            fmt::format("{} belongs to --protocol 3ifc (rating runs have no staircase)", option->get_name()));
  const SimConfig config = hil_config(o);
  const study::SessionHeader header = header_of(o, config);
  const std::unique_ptr<study::Procedure> procedure = study::make_procedure(header);
  // Atomic: a session cut short leaves no log (a simulated pair's state cannot be resumed; run it again instead).
  program::OutputFile log(o.log, "--log");
  log.write(study::to_json(header).dump() + "\n");

  SimulatedPair pair(config);
  Progress progress;
  pair.power_up();
  const double open_interval_s = header.config.at("interval_s").get<double>();
  Session session(o, pair, open_interval_s);
  session.learn_baseline();

  // The observer's own stream, apart from the procedure's, as lever-study simulate-session draws it.
  lever::Rng rng(o.seed ^ 0x9e3779b97f4a7c15ULL);
  const study::WeibullObserver detector{o.threshold, o.slope, o.lapse};
  const study::RatingObserver rater;
  int attempt = 0, voids = 0;
  const Nanos session_start = pair.now();
  while (!procedure->done()) {
    const study::Trial trial = procedure->current();
    auto record = study::record_of(trial, ++attempt);
    progress.update(attempt, static_cast<double>(pair.now() - session_start) * 1e-9);
    std::optional<std::string> void_reason;
    session.present(trial, record, void_reason);
    if (void_reason) {
      record.void_reason = *void_reason;
      ++voids;
      procedure->void_trial();
    } else if (trial.takes_answer()) {
      // The answer comes from the model, not from the traffic: the HIL gives the intervals, the observer the answer.
      const int answer = trial.kind == study::Kind::three_ifc ? detector.answer(trial, rng) : rater.rate(trial, rng);
      record.answer = answer;
      if (trial.kind == study::Kind::three_ifc) record.right = answer == trial.carrier;
      procedure->answer(answer);
    } else {
      procedure->acknowledge();
    }
    log.write(study::to_json(record).dump() + "\n");
  }
  log.commit();
  const double simulated_s = static_cast<double>(pair.now() - session_start) * 1e-9;
  fmt::print(
      "lever-hil study: SIMULATED session of {} ({}) on the HIL's pair ({}, {} gauge, seed {}) written to {}: {} "
      "records ({} void), {:.0f} s simulated in {:.1f} s\n",
      program::printable(o.subject), o.protocol, name(config.topology), gauge_chain_name(config), o.seed,
      program::printable(o.log), attempt, voids, simulated_s, progress.wall_s());
  return 0;
}

}  // namespace lever::hil
