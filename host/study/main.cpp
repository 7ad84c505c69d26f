// lever-study: the paper's user-study procedures off the bench. `simulate` runs the 3IFC staircase many times for a
// simulated observer of known threshold and reports what it estimates; `report` summarises session logs as the
// paper's Fig. 7, Fig. 8 and Fig. 11 do (report.cpp, docs/study.md).
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "lever/program/choices.hpp"
#include "lever/program/numbers.hpp"
#include "lever/program/parse.hpp"
#include "lever/program/text.hpp"
#include "lever/study/observer.hpp"
#include "lever/study/rating.hpp"
#include "lever/study/session_log.hpp"
#include "lever/study/three_ifc.hpp"
#include "report.hpp"
#include "session_runner.hpp"

namespace {

namespace program = lever::program;
namespace study = lever::study;
using Clock = std::chrono::steady_clock;

enum class Format { text, json, csv };
constexpr std::string_view name(Format f) { return f == Format::text ? "text" : f == Format::json ? "json" : "csv"; }

struct SimulateOptions {
  std::vector<double> thresholds{0.05, 0.10, 0.15};
  double slope = 3.0;
  double lapse = 0.02;
  int sessions = 1000;
  std::uint64_t seed = 1;
  Format format = Format::text;
  study::ThreeIfcConfig config;
};

struct SessionOptions {
  std::string protocol = "3ifc";
  std::string subject = "sim";
  std::uint64_t seed = 1;
  std::string log;
  bool resume = false;
  double threshold = 0.12;
  double slope = 3.0;
  double lapse = 0.02;
};

struct RunOptions {
  study::RunnerOptions runner;
  std::string protocol = "3ifc";
  std::optional<std::uint64_t> seed;
  int pair = 0;
  study::ThreeIfcConfig three_ifc;
  study::RatingConfig rating;
  std::optional<double> interval_s;
};

int fail(int code, const std::string& message) {
  fmt::print(stderr, "lever-study: {}\n", message);
  return code;
}

nlohmann::json spread_json(const study::Spread& s, double truth) {
  return {{"n", s.n},
          {"median", s.median},
          {"q1", s.q1},
          {"q3", s.q3},
          {"iqr", s.iqr()},
          {"mean", s.mean},
          {"sd", s.sd},
          {"min", s.min},
          {"max", s.max},
          {"bias_median", s.median - truth},
          {"bias_mean", s.mean - truth}};
}

// A progress line on stderr once a run has taken a second, so a long run shows it is alive; none on short ones.
class Progress {
 public:
  explicit Progress(long total) : total_(total), tty_(::isatty(STDERR_FILENO) == 1) {}
  void update(long done) {
    const auto now = Clock::now();
    if (now - start_ < std::chrono::seconds(1) || now - last_ < std::chrono::milliseconds(500)) return;
    last_ = now;
    shown_ = true;
    fmt::print(stderr, "{}lever-study: simulated {}/{} sessions{}", tty_ ? "\r" : "", done, total_, tty_ ? "" : "\n");
  }
  ~Progress() {
    if (shown_ && tty_) fmt::print(stderr, "\n");
  }

 private:
  long total_;
  bool tty_;
  bool shown_ = false;
  Clock::time_point start_ = Clock::now(), last_{};
};

int simulate(const SimulateOptions& o) {
  try {
    study::check(o.config);
  } catch (const std::invalid_argument& e) {
    return fail(2, e.what());
  }
  nlohmann::json results = nlohmann::json::array();
  Progress progress(static_cast<long>(o.sessions) * static_cast<long>(o.thresholds.size()));
  long done = 0;
  lever::Rng seeder(o.seed);
  for (const double threshold : o.thresholds) {
    const study::WeibullObserver observer{threshold, o.slope, o.lapse};
    std::vector<double> per_pass[3], overall;
    int not_reached = 0;
    long trials = 0;
    for (int s = 0; s < o.sessions; ++s) {
      const auto run = study::simulate_three_ifc(o.config, observer, seeder.next());
      for (std::size_t i = 0; i < run.passes.size() && i < 3; ++i) per_pass[i].push_back(run.passes[i].p);
      overall.push_back(run.threshold.value_or(0.0));
      if (!run.reached) ++not_reached;
      trials += run.trials;
      progress.update(++done);
    }
    nlohmann::json passes = nlohmann::json::array();
    for (int i = 0; i < 3; ++i) {
      auto j = spread_json(study::spread_of(per_pass[i]), threshold);
      j["pass"] = i + 1;
      passes.push_back(j);
    }
    results.push_back({{"threshold", threshold},
                       {"p_right_at_threshold", observer.p_right(threshold)},
                       {"trials_mean", static_cast<double>(trials) / o.sessions},
                       {"not_reached", not_reached},
                       {"passes", passes},
                       {"overall", spread_json(study::spread_of(overall), threshold)}});
  }
  const nlohmann::json observer = {{"model", "weibull"}, {"slope", o.slope}, {"lapse", o.lapse}, {"guess", 1.0 / 3.0}};
  const char* label = "SIMULATED observers, not data: they reproduce nothing of the paper's Fig. 7";
  if (o.format == Format::json) {
    fmt::print("{}\n", nlohmann::json{{"simulated", true},
                                      {"note", label},
                                      {"observer", observer},
                                      {"procedure", study::to_json(o.config)},
                                      {"sessions", o.sessions},
                                      {"seed", o.seed},
                                      {"results", results}}
                           .dump(2));
    return 0;
  }
  if (o.format == Format::csv) {
    fmt::print(
        "simulated,threshold,slope,lapse,sessions,estimate,n,median,q1,q3,iqr,mean,sd,bias_median,bias_mean,"
        "not_reached,trials_mean\n");
    for (const auto& r : results) {
      const auto row = [&](const std::string& what, const nlohmann::json& s) {
        fmt::print("true,{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", r["threshold"].get<double>(), o.slope,
                   o.lapse, o.sessions, what, s["n"].get<int>(), s["median"].get<double>(), s["q1"].get<double>(),
                   s["q3"].get<double>(), s["iqr"].get<double>(), s["mean"].get<double>(), s["sd"].get<double>(),
                   s["bias_median"].get<double>(), s["bias_mean"].get<double>(), r["not_reached"].get<int>(),
                   r["trials_mean"].get<double>());
      };
      for (const auto& pass : r["passes"]) row(fmt::format("pass{}", pass["pass"].get<int>()), pass);
      row("threshold", r["overall"]);
    }
    return 0;
  }
  fmt::print("{}\n", label);
  fmt::print("observer: Weibull, guess 1/3, slope {}, lapse {}; {} sessions a threshold, seed {}\n",
             program::short_number(o.slope), program::short_number(o.lapse), o.sessions, o.seed);
  fmt::print("{:>9}  {:>9}  {:>7} {:>7} {:>7} {:>7} {:>7} {:>7}  {:>8} {:>8}  {:>11}  {:>6}\n", "threshold", "estimate",
             "median", "q1", "q3", "IQR", "mean", "sd", "bias med", "bias mean", "not reached", "trials");
  for (const auto& r : results) {
    const auto row = [&](const std::string& what, const nlohmann::json& s) {
      fmt::print(
          "{:>8.2f}%  {:>9}  {:>6.2f}% {:>6.2f}% {:>6.2f}% {:>6.2f}% {:>6.2f}% {:>6.2f}%  {:>+7.2f}% {:>+8.2f}%  "
          "{:>11}  {:>6.1f}\n",
          100 * r["threshold"].get<double>(), what, 100 * s["median"].get<double>(), 100 * s["q1"].get<double>(),
          100 * s["q3"].get<double>(), 100 * s["iqr"].get<double>(), 100 * s["mean"].get<double>(),
          100 * s["sd"].get<double>(), 100 * s["bias_median"].get<double>(), 100 * s["bias_mean"].get<double>(),
          r["not_reached"].get<int>(), r["trials_mean"].get<double>());
    };
    for (const auto& pass : r["passes"]) row(fmt::format("pass {}", pass["pass"].get<int>()), pass);
    row("threshold", r["overall"]);
  }
  return 0;
}

// A whole session answered by a simulated observer and written to a session log as a runner writes one, so the
// log's format, its resume and `report` can be tried without a pair.
int simulated_session(const SessionOptions& o) {
  try {
    std::unique_ptr<study::Procedure> procedure;
    std::optional<study::SessionLogWriter> writer;
    int attempt = 0;
    if (o.resume) {
      const auto log = study::read_session_log(o.log);
      for (const auto& w : log.warnings) fmt::print(stderr, "lever-study: warning: {}\n", program::printable(w));
      if (!log.header.simulated) return fail(2, fmt::format("{}: not a simulated session", program::printable(o.log)));
      // Its intervals ran on the HIL's pair, whose state is not in the log: going on without it would mix sessions.
      if (!log.header.simulator.is_null())
        return fail(2, fmt::format("{}: a session on lever-hil's simulated pair: run lever-hil study again instead",
                                   program::printable(o.log)));
      procedure = study::resume(log);
      writer.emplace(study::SessionLogWriter::resume(o.log, log));
      attempt = static_cast<int>(log.records.size());
    } else {
      const study::SessionHeader header{
          o.protocol, o.subject, o.seed, true,
          o.protocol == "3ifc" ? study::to_json(study::ThreeIfcConfig{}) : study::to_json(study::RatingConfig{})};
      procedure = study::make_procedure(header);
      writer.emplace(study::SessionLogWriter::create(o.log, header));
    }
    // The observer's own stream, apart from the procedure's; a resumed session draws a new one from where it resumed.
    lever::Rng rng(o.seed ^ (0x9e3779b97f4a7c15ULL * static_cast<std::uint64_t>(attempt + 1)));
    const study::WeibullObserver detector{o.threshold, o.slope, o.lapse};
    const study::RatingObserver rater;
    while (!procedure->done()) {
      const study::Trial t = procedure->current();
      auto record = study::record_of(t, ++attempt);
      if (t.takes_answer()) {
        const int answer = t.kind == study::Kind::three_ifc ? detector.answer(t, rng) : rater.rate(t, rng);
        record.answer = answer;
        if (t.kind == study::Kind::three_ifc) record.right = answer == t.carrier;
        writer->append(record);
        procedure->answer(answer);
      } else {
        writer->append(record);
        procedure->acknowledge();
      }
    }
    fmt::print("lever-study: SIMULATED session of {} ({}) written to {}: {} records\n", program::printable(o.subject),
               procedure->protocol(), program::printable(o.log), attempt);
    return 0;
  } catch (const study::SessionLogError& e) {
    return fail(2, program::printable(e.what()));
  }
}

}  // namespace

// A session on a pair. A new log takes its seed from --seed or, by default, from the system's random source, and
// writes it in its header; an existing one is resumed under its own header, whatever the options say.
int run(RunOptions o) {
  auto& header = o.runner.header;
  header.protocol = o.protocol;
  header.simulated = false;
  header.seed = o.seed ? *o.seed : (static_cast<std::uint64_t>(std::random_device{}()) << 32) ^ std::random_device{}();
  if (o.interval_s) {
    o.three_ifc.interval_s = *o.interval_s;
    o.rating.interval_s = *o.interval_s;
  }
  header.config = o.protocol == "3ifc" ? study::to_json(o.three_ifc) : study::to_json(o.rating);
  o.runner.pair = static_cast<std::uint8_t>(o.pair);
  try {
    if (std::filesystem::exists(o.runner.log)) {
      const auto log = study::read_session_log(o.runner.log);
      if (log.header.simulated)
        return fail(2,
                    fmt::format("{}: a simulated session, not one to run on a pair", program::printable(o.runner.log)));
    } else if (header.subject.empty()) {
      return fail(2, "a new session needs --subject (the subject's name or code, written in the log)");
    }
    return study::run_session(o.runner);
  } catch (const study::SessionLogError& e) {
    return fail(2, program::printable(e.what()));
  } catch (const std::invalid_argument& e) {
    return fail(2, program::printable(e.what()));
  }
}

// The 3IFC staircase's options, for simulate and run alike.
void add_staircase_options(CLI::App& cmd, study::ThreeIfcConfig& c, const std::string& prefix) {
  cmd.add_option("--start-p", c.start_p, prefix + "p of a pass's first trial (paper: 0.025)")
      ->check(program::number(program::kWeberFraction));
  cmd.add_option("--step", c.step, prefix + "the rise of p after a wrong answer (our reading: 0.025)")
      ->check(program::number({0.0, 1.0, true, true, "a fraction"}));
  cmd.add_option("--max-p", c.max_p, prefix + "the largest p (paper: 0.25)")
      ->check(program::number({0.0, 1.0, true, true, "a fraction"}));
  cmd.add_option("--right-in-a-row", c.right_in_a_row, prefix + "right answers in a row that end a pass (paper: 3)")
      ->check(program::whole(1, 100));
}

CLI::App* add_simulate_command(CLI::App& app, SimulateOptions& s) {
  CLI::App* sim =
      app.add_subcommand("simulate", "N simulated 3IFC sessions per threshold: the staircase's bias and spread");
  sim->add_option("--thresholds", s.thresholds, "the simulated observers' thresholds (Weibull alpha), comma-separated")
      ->delimiter(',')
      ->check(program::number({0.0, 1.0, true, true, "a fraction"}))
      ->default_str("0.05,0.10,0.15");
  sim->add_option("--slope", s.slope, "the Weibull slope beta")
      ->check(program::number({0.0, 100.0, true, false, "a slope"}))
      ->default_str("3");
  sim->add_option("--lapse", s.lapse, "the lapse rate lambda")
      ->check(program::number({0.0, 0.5, false, true, "a rate"}))
      ->default_str("0.02");
  sim->add_option("--sessions", s.sessions, "sessions per threshold")
      ->check(program::whole(1, 10000000))
      ->default_str("1000");
  sim->add_option("--seed", s.seed, "the seed of every session's procedure and observer")
      ->check(program::seed())
      ->default_str("1");
  static const auto formats = program::choices_of({Format::text, Format::json, Format::csv});
  sim->add_option("--format", s.format, "text, json or csv")->transform(program::one_of(formats))->default_str("text");
  add_staircase_options(*sim, s.config, "");
  sim->add_option("--pass3-factor", s.config.pass3_factor, "pass 3 starts at this times pass 2's result (paper: 0.5)")
      ->check(program::number({0.0, 1.0, true, false, "a factor"}));
  sim->add_option("--max-trials-per-pass", s.config.max_trials_per_pass,
                  "a pass that has not stopped after this many trials ends, not reached (not the paper's; 60)")
      ->check(program::whole(1, 10000));
  return sim;
}

CLI::App* add_session_command(CLI::App& app, SessionOptions& so) {
  CLI::App* ses = app.add_subcommand(
      "simulate-session", "one whole session answered by a simulated observer, written to a session log (or resumed)");
  ses->add_option("--protocol", so.protocol, "3ifc or rating")
      ->check(CLI::IsMember({"3ifc", "rating"}))
      ->default_str("3ifc");
  ses->add_option("--log", so.log, "the session log to write (refused if it exists, unless --resume)")
      ->required()
      ->check(program::path());
  ses->add_flag("--resume", so.resume, "go on with the session in --log from its last complete record");
  ses->add_option("--subject", so.subject, "the subject's name in the log")->default_str("sim");
  ses->add_option("--seed", so.seed, "the seed of the procedure (in the log) and the observer")
      ->check(program::seed())
      ->default_str("1");
  ses->add_option("--threshold", so.threshold, "3ifc: the observer's threshold (Weibull alpha)")
      ->check(program::number({0.0, 1.0, true, true, "a fraction"}))
      ->default_str("0.12");
  ses->add_option("--slope", so.slope, "3ifc: the Weibull slope beta")
      ->check(program::number({0.0, 100.0, true, false, "a slope"}))
      ->default_str("3");
  ses->add_option("--lapse", so.lapse, "3ifc: the lapse rate lambda")
      ->check(program::number({0.0, 0.5, false, true, "a rate"}))
      ->default_str("0.02");
  return ses;
}

CLI::App* add_run_command(CLI::App& app, RunOptions& ro) {
  CLI::App* run_cmd = app.add_subcommand(
      "run", "a session on a pair: the intervals on the levers, the answers from this terminal or a program");
  run_cmd->add_option("--can", ro.runner.can, "the pair's CAN interface")->required();
  run_cmd->add_option("--pair", ro.pair, "the pair's number")->check(program::whole(0, 15))->default_str("0");
  run_cmd->add_option("--log", ro.runner.log, "the session log: created, or resumed from its last complete trial")
      ->required()
      ->check(program::path());
  run_cmd->add_option("--protocol", ro.protocol, "3ifc or rating (a new session)")
      ->check(CLI::IsMember({"3ifc", "rating"}))
      ->default_str("3ifc");
  run_cmd->add_option("--subject", ro.runner.header.subject, "the subject's name or code (a new session)");
  run_cmd->add_option("--seed", ro.seed, "the seed of the carriers or the order (a new session; default: random)")
      ->check(program::seed());
  run_cmd->add_option("--progress", ro.runner.progress,
                      "the experimenter's view (p, carriers, answers), appended to this file, FIFO or terminal");
  run_cmd->add_option("--interval-s", ro.interval_s, "an interval's length (paper: 20 s for 3ifc, 30 s for rating)")
      ->check(program::number({0.1, 600.0, false, false, "a time in seconds"}));
  run_cmd->add_option("--gap-s", ro.three_ifc.gap_s, "3ifc: the pause between a trial's intervals (our reading: 1)")
      ->check(program::number({0.0, 60.0, false, false, "a time in seconds"}));
  add_staircase_options(*run_cmd, ro.three_ifc, "3ifc: ");
  run_cmd
      ->add_option("--confirm-timeout", ro.runner.confirm_timeout_s,
                   "seconds for a lever to show an interval's settings (then the trial is void)")
      ->check(program::number({0.05, 60.0, false, false, "a time in seconds"}))
      ->default_str("1");
  run_cmd
      ->add_option("--ready-timeout", ro.runner.ready_timeout_s,
                   "seconds to wait for the pair to be armed, homed and free of faults before a trial")
      ->check(program::number({1.0, 86400.0, false, false, "a time in seconds"}))
      ->default_str("300");
  return run_cmd;
}

// lever-study report's options: the report's own, and how they were given.
struct ReportCommand {
  CLI::App* app = nullptr;
  study::ReportOptions options;
  Format format = Format::text;
  CLI::Option* table = nullptr;
};

void add_report_command(CLI::App& app, ReportCommand& rc) {
  study::ReportOptions& r = rc.options;
  rc.app = app.add_subcommand(
      "report",
      "per-subject thresholds (Fig. 7), traffic against p (Fig. 8) and ratings against p (Fig. 11) from session logs");
  rc.app->add_option("logs", r.logs, "session logs (JSON Lines)")->required()->check(program::path());
  static const auto formats = program::choices_of({Format::text, Format::csv});
  rc.app->add_option("--format", rc.format, "text or csv")->transform(program::one_of(formats))->default_str("text");
  static const auto tables = program::choices_of(study::kAllReportTables);
  rc.table = rc.app
                 ->add_option("--table", r.table,
                              "thresholds, traffic or ratings: the one table of --format csv (default thresholds); "
                              "with text, that table alone (default: every table the logs fill)")
                 ->transform(program::one_of(tables))
                 ->default_str("thresholds");
  rc.app
      ->add_option("--plots", r.plots,
                   "a directory (made if missing) for fig7.png, fig8.png and fig11.png (those the logs fill), the "
                   "tables as CSV and plots.gp, drawn by gnuplot")
      ->check(program::path());
}

int report(ReportCommand rc) {
  rc.options.csv = rc.format == Format::csv;
  rc.options.table_given = rc.table->count() > 0;
  return study::report(rc.options);
}

int main(int argc, char** argv) {
  CLI::App app{
      "The paper's user-study procedures (Hinterseer et al., IV-A-2 and IV-B-3): run presents a session on a pair\n"
      "(the settings of every interval confirmed by the levers, every trial in a session log, resumable); simulate "
      "runs the\n"
      "3IFC detection-threshold staircase for simulated observers of known threshold and reports the bias and\n"
      "spread of what it estimates; report summarises session logs (docs/study.md)."};
  program::describe(app, "lever-study");
  app.footer(
      "Exit status: 0 done; 1 a runtime failure (run: the bus or the pair; the log keeps every trial so far; report\n"
      "--plots: a directory that cannot be made, gnuplot missing or failed); 2 bad input (an option, a session log\n"
      "that is missing, damaged, or does not match its own config and seed, a --plots that is a file); 3 run: the\n"
      "answers' input ended before the session; 130 run: stopped by SIGINT or SIGTERM.");
  SimulateOptions simulate_options;
  CLI::App* simulate_cmd = add_simulate_command(app, simulate_options);
  SessionOptions session_options;
  CLI::App* session_cmd = add_session_command(app, session_options);
  RunOptions run_options;
  CLI::App* run_cmd = add_run_command(app, run_options);
  ReportCommand report_command;
  add_report_command(app, report_command);
  app.require_subcommand(1);

  if (const auto stop = program::parse(app, argc, argv)) return *stop;
  if (run_cmd->parsed()) return run(run_options);
  if (simulate_cmd->parsed()) return simulate(simulate_options);
  if (session_cmd->parsed()) return simulated_session(session_options);
  return report(std::move(report_command));
}
