#include "session_runner.hpp"

#include <fmt/format.h>
#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "lever/board/socketcan.hpp"
#include "lever/study/answer_lines.hpp"
#include "lever/study/pair_watch.hpp"

namespace lever::study {

namespace {

using Clock = std::chrono::steady_clock;
using protocol::Direction;
using protocol::Role;

volatile std::sig_atomic_t stop_signal = 0;
extern "C" void on_stop_signal(int signal) { stop_signal = signal; }

// SIGINT and SIGTERM end the session between two reads: poll returns EINTR (no SA_RESTART), the runner puts the
// levers' settings back and exits. The log has every complete trial already.
void catch_stop_signals() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

constexpr Direction kDirections[] = {Direction::motion, Direction::force};

struct Stop {
  int code;
  std::string why;
};

// The session's I/O: the bus read into the pair's watch, the answers' lines, the subject's prompts and the
// experimenter's progress. One poll on the CAN socket and the answers' input, so the watch stays current while
// the runner waits for an answer.
class SessionIo {
 public:
  SessionIo(board::SocketCan can, std::uint8_t pair, std::FILE* progress)
      : can_(std::move(can)), watch_(pair), pair_(pair), progress_(progress) {}

  PairWatch& watch() { return watch_; }
  std::int64_t now_us() const { return watch_.newest_us(); }

  // To the subject: never p, never which interval carries it.
  void say(const std::string& text) {
    std::fputs(text.c_str(), stdout);
    std::fputc('\n', stdout);
    std::fflush(stdout);
  }
  // To the experimenter only.
  void progress(const std::string& text) {
    if (progress_ == nullptr) return;
    std::fputs(text.c_str(), progress_);
    std::fputc('\n', progress_);
    std::fflush(progress_);
  }

  // Reads the bus (and, when `line` is given, the answers' input) for up to `wait`; returns early once a whole
  // line is in. A Stop for a signal, a bus that failed, or the answers' end while a line was wanted.
  std::optional<Stop> pump(Clock::duration wait, std::optional<AnswerLine>* line = nullptr) {
    const auto deadline = Clock::now() + wait;
    while (true) {
      if (stop_signal != 0) return Stop{kSessionInterrupted, fmt::format("stopped by signal {}", int{stop_signal})};
      if (line != nullptr && (*line = input_.take())) return std::nullopt;
      if (line != nullptr && input_.ended()) return Stop{kAnswersEnded, "the answers' input ended"};
      const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now()).count();
      if (left <= 0) return std::nullopt;
      pollfd fds[2] = {{can_.fd(), POLLIN, 0}, {STDIN_FILENO, POLLIN, 0}};
      const nfds_t count = line != nullptr ? 2 : 1;
      if (::poll(fds, count, static_cast<int>(std::min<long long>(left, 100))) < 0) {
        if (errno == EINTR) continue;
        return Stop{kSessionFailed, fmt::format("poll: {}", std::strerror(errno))};
      }
      if (auto stop = drain()) return stop;
      if (count == 2 && (fds[1].revents & (POLLIN | POLLHUP)) != 0) read_input();
    }
  }

  std::optional<Stop> send(const protocol::CommandMessage& m) {
    const auto status = can_.write(protocol::pack(m, pair_));
    // would_block: the queue is full; the confirmation's wait sends another copy.
    if (status == board::IoStatus::ok || status == board::IoStatus::would_block) return std::nullopt;
    return failed("sending on", status);
  }

 private:
  Stop failed(const char* doing, board::IoStatus status) const {
    if (status == board::IoStatus::interface_down)
      return Stop{kSessionFailed, fmt::format("{} is down", can_.interface())};
    if (status == board::IoStatus::interface_gone)
      return Stop{kSessionFailed, fmt::format("{} is gone", can_.interface())};
    return Stop{kSessionFailed, fmt::format("{} {}: {}", doing, can_.interface(), std::strerror(can_.last_errno()))};
  }

  std::optional<Stop> drain() {
    protocol::CanFrame frame;
    std::int64_t t_us = 0;
    while (true) {
      const auto status = can_.read(frame, t_us);
      if (status == board::IoStatus::ok) {
        watch_.on_frame(frame, t_us);
      } else if (status == board::IoStatus::would_block) {
        return std::nullopt;
      } else if (status != board::IoStatus::skipped && status != board::IoStatus::error_frame) {
        return failed("reading", status);
      }
    }
  }

  // Read only while no whole line waits (pump takes one first), so the lines held stay within one read.
  void read_input() {
    char buffer[256];
    const ssize_t n = ::read(STDIN_FILENO, buffer, sizeof buffer);
    if (n > 0) {
      input_.feed({buffer, static_cast<std::size_t>(n)});
    } else if (n == 0 || (errno != EINTR && errno != EAGAIN)) {
      input_.end();
    }
  }

  board::SocketCan can_;
  PairWatch watch_;
  std::uint8_t pair_;
  std::FILE* progress_;
  AnswerLines input_;
};

std::chrono::microseconds seconds(double s) { return std::chrono::microseconds(static_cast<std::int64_t>(s * 1e6)); }

class Runner {
 public:
  Runner(const RunnerOptions& options, SessionIo& io) : options_(options), io_(io) {}

  int run() {
    const bool resuming = std::filesystem::exists(options_.log);
    std::unique_ptr<Procedure> procedure;
    std::optional<SessionLogWriter> writer;
    int attempt = 0;
    if (resuming) {
      const auto contents = read_session_log(options_.log);
      for (const auto& w : contents.warnings) fmt::print(stderr, "lever-study: {}\n", w);
      procedure = resume(contents);
      writer.emplace(SessionLogWriter::resume(options_.log, contents));
      attempt = static_cast<int>(contents.records.size());
      header_ = contents.header;
      io_.progress(
          fmt::format("resumed {}: {} records, subject {}", options_.log, contents.records.size(), header_.subject));
    } else {
      header_ = options_.header;
      procedure = make_procedure(header_);
      writer.emplace(SessionLogWriter::create(options_.log, header_));
      io_.progress(fmt::format("new session {}: {} for subject {}, seed {}", options_.log, header_.protocol,
                               header_.subject, header_.seed));
    }
    if (auto stop = learn_baseline()) return finish(*stop, false);

    while (!procedure->done()) {
      const Trial& trial = procedure->current();
      TrialRecord record = record_of(trial, ++attempt);
      io_.progress(fmt::format("attempt {}: {} pass {} trial {}: p {:.2f} % on {}{}", attempt, name(trial.kind),
                               trial.pass, trial.trial, trial.p * 100.0, name(trial.direction),
                               trial.carrier != 0 ? fmt::format(", carried by interval {}", trial.carrier) : ""));
      std::optional<std::string> void_reason;
      if (auto stop = present(trial, record, void_reason)) return finish(*stop, true);
      if (void_reason) {
        record.void_reason = *void_reason;
        writer->append(record);
        procedure->void_trial();
        io_.say("That trial is repeated.");
        io_.progress(fmt::format("  void: {}", *void_reason));
        continue;
      }
      if (trial.takes_answer()) {
        int answer = 0;
        if (auto stop = ask(trial, answer)) return finish(*stop, true);
        const auto outcome = procedure->answer(answer);
        record.answer = answer;
        record.right = outcome.right;
        writer->append(record);
        io_.progress(fmt::format("  answer {}{}", answer,
                                 outcome.right ? (*outcome.right ? ": right" : ": wrong") : std::string()));
      } else {
        writer->append(record);
        procedure->acknowledge();
      }
    }
    io_.say("The session is over. Thank you.");
    return finish(Stop{kSessionDone, "the session is over"}, true);
  }

 private:
  // Each lever's settings before the session: the mode, floor and prefilter every interval keeps, and what the
  // levers are given back at the end.
  std::optional<Stop> learn_baseline() {
    const auto deadline = Clock::now() + seconds(options_.ready_timeout_s);
    while (true) {
      bool all = true;
      for (const auto d : kDirections) all = all && io_.watch().lever(sender_of(d)).settings.has_value();
      if (all) break;
      if (Clock::now() >= deadline) {
        std::string missing;
        for (const auto d : kDirections)
          if (!io_.watch().lever(sender_of(d)).settings)
            missing += fmt::format("{}{}", missing.empty() ? "" : " and ", role_name(sender_of(d)));
        return Stop{kSessionFailed, fmt::format("no settings frame from the {} within {} s on {} (pair {}): is the "
                                                "lever running, and its firmware one that sends them?",
                                                missing, options_.ready_timeout_s, options_.can, options_.pair)};
      }
      if (auto stop = io_.pump(std::chrono::milliseconds(100))) return stop;
    }
    for (const auto d : kDirections) {
      baseline_[static_cast<std::size_t>(d)] = *io_.watch().lever(sender_of(d)).settings;
      io_.progress(fmt::format("the {}'s settings before the session: {}", role_name(sender_of(d)),
                               describe(baseline_[static_cast<std::size_t>(d)])));
    }
    return std::nullopt;
  }

  // Until the pair can carry an interval; the experimenter is told what is wrong once, and again when it changes.
  std::optional<Stop> wait_ready() {
    const auto deadline = Clock::now() + seconds(options_.ready_timeout_s);
    std::string told;
    while (true) {
      const auto why = io_.watch().not_ready(io_.now_us());
      if (why.empty()) return std::nullopt;
      if (why != told) {
        io_.progress(fmt::format("  waiting for the pair: {}", why));
        told = why;
      }
      if (Clock::now() >= deadline)
        return Stop{kSessionFailed, fmt::format("the pair was not ready for {} s: {}", options_.ready_timeout_s, why)};
      if (auto stop = io_.pump(std::chrono::milliseconds(50))) return stop;
    }
  }

  // Asks the path's sending lever for `wanted` and waits until its settings frame shows it took it (the counter
  // moved on, the values asked for), sending a copy every 200 ms (a lost command frame). False when the lever has
  // not within the confirmation timeout; a Stop for a signal or a bus that failed.
  std::optional<Stop> confirm(Direction d, const protocol::SettingsMessage& wanted, bool& taken) {
    const auto& seen = io_.watch().lever(sender_of(d));
    const std::uint8_t before = seen.settings ? seen.settings->changes : 0;
    const auto deadline = Clock::now() + seconds(options_.confirm_timeout_s);
    auto next_copy = Clock::now();
    taken = false;
    while (!(seen.settings && confirms(*seen.settings, before, wanted))) {
      if (Clock::now() >= deadline) return std::nullopt;
      if (Clock::now() >= next_copy) {
        if (auto stop = io_.send(command_for(d, wanted))) return stop;
        next_copy = Clock::now() + std::chrono::milliseconds(200);
      }
      if (auto stop = io_.pump(std::chrono::milliseconds(20))) return stop;
    }
    taken = true;
    return std::nullopt;
  }

  // The interval's settings on both levers, each confirmed; a lever that does not confirm leaves `why` set.
  std::optional<Stop> apply(const Interval& interval, nlohmann::json& confirmed, std::optional<std::string>& why) {
    for (const auto d : kDirections) {
      const Role role = sender_of(d);
      const auto wanted = settings_for(interval, d, baseline_[static_cast<std::size_t>(d)]);
      bool taken = false;
      if (auto stop = confirm(d, wanted, taken)) return stop;
      const auto& seen = io_.watch().lever(role);
      if (!taken) {
        why = fmt::format("the {} did not confirm {} within {} s (its settings frame: {})", role_name(role),
                          describe(wanted), options_.confirm_timeout_s,
                          seen.settings ? describe(*seen.settings) : std::string("none"));
        return std::nullopt;
      }
      confirmed[role == Role::hsi ? "hsi" : "top"] = settings_json(*seen.settings, seen.settings_us);
      confirmed_[static_cast<std::size_t>(role)] = *seen.settings;
    }
    return std::nullopt;
  }

  // What voids a running interval: a lever not armed, unhomed, faulted or unheard, or a settings frame that no
  // longer shows what was confirmed (someone else's command, a lever restarted). Its change counter may move on
  // without harm: a second copy of the command, sent before the first one's confirmation came, counts again.
  std::string spoiled() const {
    auto why = io_.watch().not_ready(io_.now_us());
    if (!why.empty()) return why;
    for (const auto role : {Role::hsi, Role::top}) {
      const auto& seen = io_.watch().lever(role);
      const auto& want = confirmed_[static_cast<std::size_t>(role)];
      if (seen.settings && !protocol::same_codec_settings(*seen.settings, want))
        return fmt::format("the {}'s settings changed to {}", role_name(role), describe(*seen.settings));
    }
    return {};
  }

  std::optional<Stop> present(const Trial& trial, TrialRecord& record, std::optional<std::string>& void_reason) {
    const auto count = trial.intervals.size();
    if (trial.kind == Kind::familiarization)
      io_.say("Familiarization: operate the lever and feel the wall. Press Enter when you are familiar with it.");
    else if (trial.kind == Kind::briefing)
      io_.say("This is what the distortion feels like. Press Enter when you have felt it.");
    else if (trial.kind == Kind::three_ifc)
      io_.say(fmt::format("Trial {}: three intervals follow; one of them feels different.", trial.trial));
    for (std::size_t i = 0; i < count; ++i) {
      auto& interval_record = record.intervals[i];
      const Interval& interval = trial.intervals[i];
      // Before a trial the runner waits for the pair (the experimenter re-arms it); between two intervals of one
      // trial a pair that is not ready voids the trial, whose intervals must follow each other as the subject
      // compares them.
      if (i == 0) {
        if (auto stop = wait_ready()) return stop;
      } else if (const auto why = io_.watch().not_ready(io_.now_us()); !why.empty()) {
        void_reason = fmt::format("before interval {}: {}", i + 1, why);
        return std::nullopt;
      }
      nlohmann::json confirmed = nlohmann::json::object();
      if (auto stop = apply(interval, confirmed, void_reason)) return stop;
      if (void_reason) return std::nullopt;
      interval_record.confirmed = confirmed;
      if (const auto why = spoiled(); !why.empty()) {
        void_reason = fmt::format("before interval {}: {}", i + 1, why);
        return std::nullopt;
      }
      const auto frames_before =
          std::array{io_.watch().data_frames(Direction::motion), io_.watch().data_frames(Direction::force)};
      const std::int64_t start_us = io_.now_us();
      interval_record.start_bus_us = start_us;
      if (interval.duration_s > 0.0) {
        if (count > 1)
          io_.say(fmt::format("Interval {} of {}: now.", i + 1, count));
        else
          io_.say("Interval: now.");
        io_.progress(fmt::format("  interval {} of {}: p velocity {:.2f} %, force {:.2f} %", i + 1, count,
                                 interval.p_velocity * 100.0, interval.p_force * 100.0));
        // The interval ends with the first frame past its length on the bus's clock; the steady clock only
        // catches a bus gone silent.
        const std::int64_t end_us = start_us + static_cast<std::int64_t>(interval.duration_s * 1e6);
        const auto silent_after = Clock::now() + seconds(interval.duration_s + 1.0);
        while (io_.now_us() < end_us) {
          if (Clock::now() >= silent_after) {
            void_reason = fmt::format("interval {}: the bus went silent", i + 1);
            break;
          }
          if (auto stop = io_.pump(std::chrono::milliseconds(20))) return stop;
          if (const auto why = spoiled(); !why.empty()) {
            void_reason = fmt::format("interval {}: {}", i + 1, why);
            break;
          }
        }
        if (void_reason)
          io_.say("The interval was interrupted.");
        else
          io_.say(count > 1 ? fmt::format("Interval {} of {}: over.", i + 1, count) : "Interval: over.");
      } else {
        // Until the subject (or the experimenter at the subject's terminal) says it is enough.
        std::optional<AnswerLine> line;
        if (auto stop = io_.pump(std::chrono::hours(24), &line)) return stop;
        if (const auto why = spoiled(); !why.empty()) void_reason = fmt::format("during the interval: {}", why);
      }
      interval_record.end_bus_us = io_.now_us();
      interval_record.frames_velocity = io_.watch().data_frames(Direction::motion) - frames_before[0];
      interval_record.frames_force = io_.watch().data_frames(Direction::force) - frames_before[1];
      io_.progress(fmt::format("  interval {}: {:.3f} s on the bus, {} velocity and {} force frames", i + 1,
                               static_cast<double>(*interval_record.end_bus_us - start_us) / 1e6,
                               *interval_record.frames_velocity, *interval_record.frames_force));
      if (void_reason) return std::nullopt;
      if (i + 1 < count && trial.gap_s > 0.0) {
        if (auto stop = io_.pump(seconds(trial.gap_s))) return stop;
      }
    }
    return std::nullopt;
  }

  std::optional<Stop> ask(const Trial& trial, int& answer) {
    const std::string question =
        trial.kind == Kind::three_ifc
            ? fmt::format("Which interval felt different? Answer {} to {}:", trial.answer_min, trial.answer_max)
            : fmt::format("How did it feel? {} (as bad as the distorted example) to {} (as the undistorted one):",
                          trial.answer_min, trial.answer_max);
    io_.say(question);
    while (true) {
      std::optional<AnswerLine> line;
      if (auto stop = io_.pump(std::chrono::hours(24), &line)) return stop;
      const std::string& text = line->text;
      int value = 0;
      std::size_t used = 0;
      try {
        if (!line->too_long) value = std::stoi(text, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used > 0 && used == text.size() && value >= trial.answer_min && value <= trial.answer_max) {
        answer = value;
        return std::nullopt;
      }
      io_.say(fmt::format("Please answer a number from {} to {}.", trial.answer_min, trial.answer_max));
    }
  }

  // Gives each lever back its settings from before the session (best effort: a pair that failed may not take
  // them, which the message says), then the exit status.
  int finish(const Stop& stop, bool restore) {
    if (restore && stop.code != kSessionFailed) {
      stop_signal = 0;  // the restore's own reads; a second signal during it ends it
      for (const auto d : kDirections) {
        const auto& want = baseline_[static_cast<std::size_t>(d)];
        const auto& seen = io_.watch().lever(sender_of(d));
        if (seen.settings && protocol::same_codec_settings(*seen.settings, want)) continue;
        bool taken = false;
        const auto failed = confirm(d, want, taken);
        if (failed || !taken)
          fmt::print(stderr, "lever-study: the {} did not take back its settings ({}){}\n", role_name(sender_of(d)),
                     describe(want), failed ? ": " + failed->why : std::string());
      }
    }
    if (stop.code == kSessionDone) {
      io_.progress(fmt::format("done: {}", options_.log));
      return kSessionDone;
    }
    fmt::print(stderr, "lever-study: {}; the log {} keeps every trial before it: run again with it to resume\n",
               stop.why, options_.log);
    io_.progress(fmt::format("stopped: {}", stop.why));
    return stop.code;
  }

  const RunnerOptions& options_;
  SessionIo& io_;
  SessionHeader header_;
  std::array<protocol::SettingsMessage, 2> baseline_{};   // by direction
  std::array<protocol::SettingsMessage, 2> confirmed_{};  // by role
};

}  // namespace

int run_session(const RunnerOptions& options) {
  std::FILE* progress = nullptr;
  if (!options.progress.empty()) {
    progress = std::fopen(options.progress.c_str(), "a");
    if (progress == nullptr) {
      fmt::print(stderr, "lever-study: cannot open the progress file {}: {}\n", options.progress, std::strerror(errno));
      return kSessionFailed;
    }
  }
  struct Closer {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  const std::unique_ptr<std::FILE, Closer> progress_owner(progress);
  auto can = board::SocketCan::open({options.can, {}, 0, true});
  if (!can) {
    fmt::print(stderr, "lever-study: {}\n", can.error().message);
    return kSessionFailed;
  }
  catch_stop_signals();
  SessionIo io(std::move(can).value(), options.pair, progress);
  Runner runner(options, io);
  return runner.run();
}

}  // namespace lever::study
