#pragma once
// A study session on a pair (lever-study run): each trial's intervals presented on the levers with the settings
// both confirmed, the pair watched through every interval, the subject's answers taken from a terminal or a
// program, every trial in the session log before the next one starts (docs/study.md, "Running a session").
#include <cstdint>
#include <string>

#include "lever/study/session_log.hpp"

namespace lever::study {

struct RunnerOptions {
  std::string can;
  std::uint8_t pair = 0;
  std::string log;                 // created with `header`, or, when it exists, resumed (its own header rules)
  SessionHeader header;            // a new session's: protocol, subject, seed, configuration
  double confirm_timeout_s = 1.0;  // for a lever to show a setting in its settings frame
  double ready_timeout_s = 300.0;  // for the pair to be armed, homed and free of faults before an interval
  std::string progress;            // the experimenter's view, appended to (a file, a FIFO, another terminal); "" none
};

// Exit status of run_session.
inline constexpr int kSessionDone = 0;
inline constexpr int kSessionFailed = 1;         // the bus or the pair failed; the log keeps every trial so far
inline constexpr int kAnswersEnded = 3;          // the answers' input ended before the session did
inline constexpr int kSessionInterrupted = 130;  // SIGINT or SIGTERM

// Throws SessionLogError for a log that cannot be read or written.
int run_session(const RunnerOptions& options);

}  // namespace lever::study
