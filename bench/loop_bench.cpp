// lever-bench-loop: the wake-up latency of the board's real-time loop (RealtimeLoop) beside cyclictest's, on this
// machine, in one run: the loop serving an HSI/TOP pair of the real firmware core (bench_pair.hpp), and cyclictest
// at the same period, priority, memory locking and CPUs (those the loop was granted: without privileges both run
// best-effort), --seconds each, taking turns in --rounds (ABBA...). Prints one JSON object. A benchmark, not a test:
// the goals (p99 within 1.5x cyclictest's, no page faults in the steady part) are reported, never asserted.
//
// Both histograms count whole microseconds from the intended wake-up, truncated, and take the nearest-rank
// percentile the same way (LatencyHistogram). cyclictest is run with --default-system: it then leaves
// /dev/cpu_dma_latency alone, as the loop does, so both see the same power management (--cyclictest-tunes-pm
// lets it hold the CPUs out of deep idle states, as it does by default).
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <stop_token>
#include <string>
#include <vector>

#include "bench_pair.hpp"
#include "lever/board/latency_histogram.hpp"
#include "lever/board/realtime_loop.hpp"

extern char** environ;

namespace {

using namespace lever;
using board::LatencyHistogram;

// The board's HAL has a step clock; with it the core measures its own step times.
struct ClockedHal : bench::BenchHal {
  std::uint64_t monotonic_ns() const { return static_cast<std::uint64_t>(board::monotonic_ns()); }
};

using Json = nlohmann::ordered_json;

Json figures(const LatencyHistogram& h) {
  return {{"p50", h.percentile_us(0.50)},
          {"p99", h.percentile_us(0.99)},
          {"max", h.max_us()},
          {"samples", h.count()},
          {"overflows", h.overflows()}};
}

std::string cpu_list_text(const std::vector<unsigned>& cpus) {
  std::string text;
  for (const unsigned cpu : cpus) text += (text.empty() ? "" : ",") + std::to_string(cpu);
  return text;
}

struct CyclictestRun {
  std::vector<std::string> argv;
  std::optional<LatencyHistogram> histogram;
  std::string error;
};

// Runs cyclictest with its histogram (1 us bins up to the LatencyHistogram's) into a JSON file, and reads the
// bins back; cyclictest's own overflow count is its cycles less what the bins hold.
CyclictestRun run_cyclictest(const std::string& program, std::int64_t period_us, std::uint64_t loops, int priority,
                             bool lock_memory, const std::vector<unsigned>& cpus, bool tunes_pm) {
  CyclictestRun run;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("lever-bench-loop-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string json_path = (dir / "cyclictest.json").string();
  const std::string log_path = (dir / "cyclictest.log").string();
  run.argv = {program,
              "-q",
              "-i",
              std::to_string(period_us),
              "-l",
              std::to_string(loops),
              "-h",
              std::to_string(LatencyHistogram::kBins),
              "--json=" + json_path};
  if (priority > 0) {
    run.argv.push_back("-p" + std::to_string(priority));
  } else {
    run.argv.push_back("--policy=other");  // "-p 0" with a histogram still asks for SCHED_FIFO
  }
  if (lock_memory) run.argv.push_back("-m");
  if (!cpus.empty()) run.argv.push_back("-a" + cpu_list_text(cpus));
  if (!tunes_pm) run.argv.push_back("--default-system");

  std::vector<char*> argv;
  for (auto& a : run.argv) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  // The histogram dump goes to stdout: this program's stdout is its JSON.
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  pid_t pid = 0;
  const int spawned = ::posix_spawnp(&pid, program.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  int status = 0;
  if (spawned != 0) {
    run.error = "cannot run " + program + " (Debian package rt-tests; scripts/setup installs it)";
  } else if (::waitpid(pid, &status, 0) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::ifstream log(log_path);
    std::string first;
    std::getline(log, first);
    run.error = program + " failed (status " + std::to_string(status) + "): " + first;
  } else {
    try {
      std::ifstream in(json_path);
      const auto j = nlohmann::json::parse(in);
      const auto& thread = j.at("thread").at("0");
      LatencyHistogram h;
      std::uint64_t binned = 0;
      for (const auto& [us, count] : thread.at("histogram").items()) {
        h.add_us(std::stoull(us), count.get<std::uint64_t>());
        binned += count.get<std::uint64_t>();
      }
      const auto cycles = thread.at("cycles").get<std::uint64_t>();
      const auto max_us = thread.at("max").get<std::uint64_t>();
      if (cycles > binned) h.add_us(std::max<std::uint64_t>(max_us, LatencyHistogram::kBins), cycles - binned);
      h.note_max_us(max_us);
      run.histogram = h;
    } catch (const std::exception& e) {
      run.error = std::string("cannot read cyclictest's JSON: ") + e.what();
    }
  }
  std::error_code ignored;
  std::filesystem::remove_all(dir, ignored);
  return run;
}

// What the loop's rounds add up to.
struct RunnerTotals {
  LatencyHistogram latency;
  std::uint64_t steps = 0, late_wakes = 0, skipped_periods = 0, long_steps = 0;
  std::int64_t worst_step_ns = 0;
  std::optional<long> minor_faults = 0, major_faults = 0;  // empty if a round ended before its steady part
  bool privileged = true;
  std::string warning;
  Json granted;
  int granted_priority = 0;
  bool memory_locked = false;
  // The pair (or the trivial step's sum, so that it is not optimised away).
  bool armed_every_round = true;
  protocol::FaultBits latched = 0;
  std::uint32_t core_overruns = 0;
  fw::Tick worst_interval = 0;
  std::uint64_t worst_core_step_ns = 0;
  std::uint64_t trivial_sum = 0;
};

// One round of the loop, `periods` long, serving a fresh pair (it arms at tick 80: ticks start again at 1).
std::optional<std::string> run_loop_round(const board::RealtimeConfig& config, std::uint64_t periods, bool with_pair,
                                          RunnerTotals& totals) {
  // Everything the step touches exists before the loop starts (and is locked with it).
  const auto pair = std::make_unique<bench::BenchPair<ClockedHal>>();
  auto opened = board::RealtimeLoop::open(config);
  if (!opened) return opened.error().message;
  board::RealtimeLoop& loop = opened.value();
  std::stop_source stop;
  std::uint64_t trivial_sum = 0;
  loop.run(
      [&](fw::Tick tick) {
        if (with_pair) {
          pair->before_step(tick);
          pair->hsi.step(tick);
          pair->top.step(tick);
        } else {
          trivial_sum += tick;
        }
        if (tick >= periods) stop.request_stop();
      },
      stop.get_token());
  const auto& stats = loop.stats();
  totals.latency.add(stats.wake_latency);
  totals.steps += stats.steps;
  totals.late_wakes += stats.late_wakes;
  totals.skipped_periods += stats.skipped_periods;
  totals.long_steps += stats.long_steps;
  totals.worst_step_ns = std::max(totals.worst_step_ns, stats.worst_step_ns);
  if (totals.minor_faults && stats.minor_faults_steady) {
    *totals.minor_faults += *stats.minor_faults_steady;
    *totals.major_faults += stats.major_faults_steady.value_or(0);
  } else {
    totals.minor_faults.reset();
    totals.major_faults.reset();
  }
  totals.privileged = loop.privileged();
  totals.warning = loop.warning();
  totals.granted_priority = loop.grants().fifo_priority;
  totals.memory_locked = loop.grants().memory_locked;
  totals.granted = {{"fifo_priority", loop.grants().fifo_priority},
                    {"memory_locked", loop.grants().memory_locked},
                    {"stack_prefaulted_bytes", loop.grants().stack_prefaulted_bytes}};
  if (with_pair) {
    const auto& hsi = pair->hsi.timing().stats();
    const auto& top = pair->top.timing().stats();
    totals.armed_every_round = totals.armed_every_round && pair->armed();
    totals.latched |=
        static_cast<protocol::FaultBits>(pair->hsi.supervisor().latched() | pair->top.supervisor().latched());
    totals.core_overruns += hsi.overruns + top.overruns;
    totals.worst_interval = std::max({totals.worst_interval, hsi.worst_interval, top.worst_interval});
    totals.worst_core_step_ns = std::max({totals.worst_core_step_ns, hsi.worst_step_ns, top.worst_step_ns});
  }
  totals.trivial_sum += trivial_sum;
  return std::nullopt;
}  // the loop gives back its scheduling and memory before cyclictest runs

// What the command line asks for.
struct Options {
  double seconds = 10.0;
  std::int64_t period_us = 1000;
  int priority = 80;
  std::string cpus_text;
  std::string step_kind = "pair";
  std::string cyclictest = "cyclictest";
  bool no_lock = false;
  bool tunes_pm = false;
  int rounds = 4;
};

void add_options(CLI::App& app, Options& o) {
  app.add_option("--seconds", o.seconds, "how long each of the two, in all")
      ->check(CLI::Range(0.1, 3600.0))
      ->default_str("10");
  app.add_option("--rounds", o.rounds, "alternations of the loop and cyclictest (ABBA...)")
      ->check(CLI::Range(1, 100))
      ->default_str("4");
  app.add_option("--period-us", o.period_us, "loop period")->check(CLI::Range(50, 1'000'000))->default_str("1000");
  app.add_option("--priority", o.priority, "SCHED_FIFO priority, 0 for none")
      ->check(CLI::Range(0, 99))
      ->default_str("80");
  app.add_option("--cpus", o.cpus_text, "CPU list for both, as taskset takes it (\"1\", \"0,2-3\")");
  app.add_option("--step", o.step_kind, "what the loop runs: pair (an HSI/TOP pair of the core) or trivial")
      ->check(CLI::IsMember({"pair", "trivial"}))
      ->default_str("pair");
  app.add_option("--cyclictest", o.cyclictest, "the cyclictest program")->default_str("cyclictest");
  app.add_flag("--no-mlock", o.no_lock, "lock no memory, in either");
  app.add_flag("--cyclictest-tunes-pm", o.tunes_pm,
               "let cyclictest hold /dev/cpu_dma_latency at 0, as it does by default");
}

// The loop's configuration from the options; empty when --cpus is no CPU list.
std::optional<board::RealtimeConfig> loop_config(const Options& o) {
  board::RealtimeConfig config;
  config.period = std::chrono::microseconds(o.period_us);
  config.fifo_priority = o.priority;
  config.lock_memory = !o.no_lock;
  if (!o.cpus_text.empty()) {
    const auto cpus = board::parse_cpu_list(o.cpus_text);
    if (!cpus) return std::nullopt;
    config.cpus = *cpus;
  }
  return config;
}

// Both sides of the comparison, as measured.
struct Measured {
  RunnerTotals runner;
  LatencyHistogram reference;
  std::string reference_error, command;
};

// Rounds in the order ABBA..., so that a machine that gets busier or quieter over the run weighs on both alike. An
// error of the loop's own ends the run (returned); cyclictest's is kept in the result, and it is not run again.
std::optional<std::string> run_rounds(const Options& o, const board::RealtimeConfig& config, Measured& m) {
  const auto periods = static_cast<std::uint64_t>(o.seconds * 1e6 / static_cast<double>(o.period_us) / o.rounds);
  const bool with_pair = o.step_kind == "pair";
  bool warned = false;
  for (int round = 0; round < o.rounds; ++round) {
    for (int half = 0; half < 2; ++half) {
      const bool loop_now = (half == 0) == (round % 2 == 0);
      if (loop_now) {
        if (auto error = run_loop_round(config, periods, with_pair, m.runner)) return error;
        if (!m.runner.privileged && !warned) {
          std::fprintf(stderr, "lever-bench-loop: %s\n", m.runner.warning.c_str());
          warned = true;
        }
      } else if (m.reference_error.empty()) {
        // As the loop was granted (it runs first): unprivileged, cyclictest would refuse to start at all.
        const CyclictestRun run = run_cyclictest(o.cyclictest, o.period_us, periods, m.runner.granted_priority,
                                                 m.runner.memory_locked, config.cpus, o.tunes_pm);
        m.command.clear();
        for (const auto& a : run.argv) m.command += (m.command.empty() ? "" : " ") + a;
        if (run.histogram) {
          m.reference.add(*run.histogram);
        } else {
          m.reference_error = run.error;
        }
      }
    }
  }
  return std::nullopt;
}

Json report(const Options& o, const board::RealtimeConfig& config, const Measured& m) {
  const RunnerTotals& runner = m.runner;
  const bool with_pair = o.step_kind == "pair";
  Json out;
  out["period_us"] = o.period_us;
  out["priority"] = o.priority;
  out["seconds"] = o.seconds;
  out["rounds"] = o.rounds;
  out["step"] = with_pair ? "HSI/TOP pair of the firmware core, in-memory HAL" : "trivial";
  out["runner_us"] = figures(runner.latency);
  const Json minor_faults = runner.minor_faults ? Json(*runner.minor_faults) : Json(nullptr);
  if (m.reference_error.empty()) {
    const std::uint64_t runner_p99 = runner.latency.percentile_us(0.99);
    const std::uint64_t reference_p99 = m.reference.percentile_us(0.99);
    out["cyclictest_us"] = figures(m.reference);
    out["ratio_p99"] =
        reference_p99 > 0 ? Json(static_cast<double>(runner_p99) / static_cast<double>(reference_p99)) : Json(nullptr);
    out["goals"] = {{"p99_within_1_5x_cyclictest",
                     reference_p99 > 0 && static_cast<double>(runner_p99) <= 1.5 * static_cast<double>(reference_p99)},
                    {"no_minor_faults_steady", minor_faults == 0}};
  } else {
    out["cyclictest_us"] = nullptr;
    out["cyclictest_error"] = m.reference_error;
  }
  out["minor_faults_steady"] = minor_faults;
  out["major_faults_steady"] = runner.major_faults ? Json(*runner.major_faults) : Json(nullptr);
  out["privileged"] = runner.privileged;
  out["warning"] = runner.warning;
  out["runner"] = {{"steps", runner.steps},
                   {"late_wakes", runner.late_wakes},
                   {"skipped_periods", runner.skipped_periods},
                   {"long_steps", runner.long_steps},
                   {"worst_step_us", static_cast<double>(runner.worst_step_ns) / 1e3}};
  if (with_pair) {
    // A wake-up more than 5 periods late latches TIMING: the pair is then no longer armed.
    out["core"] = {{"armed_every_round", runner.armed_every_round},
                   {"timing_fault", protocol::has(runner.latched, protocol::Fault::timing)},
                   {"latched_fault_bits", runner.latched},
                   {"overruns", runner.core_overruns},
                   {"worst_interval_ticks", runner.worst_interval},
                   {"worst_step_us", static_cast<double>(runner.worst_core_step_ns) / 1e3}};
  } else {
    out["trivial_sum"] = runner.trivial_sum;
  }
  out["granted"] = runner.granted;
  out["cpus"] = cpu_list_text(config.cpus);
  out["mlock"] = config.lock_memory;
  out["cyclictest_command"] = m.command;
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Wake-up latency of the real-time loop beside cyclictest's, same period and priority; prints JSON."};
  app.name("lever-bench-loop");
  Options options;
  add_options(app, options);
  CLI11_PARSE(app, argc, argv);

  const auto config = loop_config(options);
  if (!config) {
    std::fprintf(stderr, "lever-bench-loop: --cpus \"%s\" is no CPU list\n", options.cpus_text.c_str());
    return 2;
  }
  Measured measured;
  if (const auto error = run_rounds(options, *config, measured)) {
    std::fprintf(stderr, "lever-bench-loop: %s\n", error->c_str());
    return 2;
  }
  std::printf("%s\n", report(options, *config, measured).dump(2).c_str());
  return measured.reference_error.empty() ? 0 : 1;
}
