#pragma once
// The session log: JSON Lines, a header then one record a trial, each appended and on disk before the next
// interval; a session resumes from it (docs/study.md, "The session log").
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "lever/study/procedure.hpp"

namespace lever::study {

inline constexpr int kLogFormat = 1;

struct SessionLogError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct SessionHeader {
  std::string protocol;  // "3ifc" or "rating"
  std::string subject;
  std::uint64_t seed = 0;
  bool simulated = false;
  nlohmann::json config = nlohmann::json::object();
  // A session run on a simulated pair (lever-hil study): the simulation's setup, its seed and its clock, which the
  // bus times are on. Null for a session on a pair and for one without any pair (lever-study simulate-session).
  nlohmann::json simulator = nullptr;
};

// An interval as presented; the runner fills the fields the procedure cannot know.
struct IntervalRecord {
  Interval interval;
  std::optional<std::int64_t> start_bus_us, end_bus_us;
  std::optional<std::uint64_t> frames_velocity, frames_force;
  nlohmann::json confirmed;  // null until the runner records what the levers' settings frames showed
};

struct TrialRecord {
  int attempt = 0;  // 1, 2, ... over the session, void records included
  Kind kind = Kind::familiarization;
  int pass = 0;
  int trial = 0;
  double p = 0.0;
  Direction direction = Direction::both;
  int carrier = 0;
  std::optional<int> answer;
  std::optional<bool> right;
  std::optional<std::string> void_reason;
  std::vector<IntervalRecord> intervals;
};

// The record of a trial as presented: the procedure's side filled in, the runner's null.
TrialRecord record_of(const Trial& t, int attempt);

// In the order docs/study.md lists the fields, so a log reads as the page does.
nlohmann::ordered_json to_json(const SessionHeader& h);
nlohmann::ordered_json to_json(const TrialRecord& r);
SessionHeader header_from_json(const nlohmann::json& j);
TrialRecord record_from_json(const nlohmann::json& j);

struct SessionLogContents {
  SessionHeader header;
  std::vector<TrialRecord> records;
  std::vector<std::string> warnings;  // a cut last line, ignored
  std::uint64_t complete_bytes = 0;   // the length of the file up to its last complete line
};

// Throws SessionLogError on a missing or bad header, or a bad line before the last.
SessionLogContents read_session_log(const std::string& path);
// The same on text already read (tests, and a log piped in).
SessionLogContents parse_session_log(const std::string& text, const std::string& name);

// Builds the procedure the header names, seeded and configured as the header says.
std::unique_ptr<Procedure> make_procedure(const SessionHeader& h);
// Feeds the records to a procedure built from the same header: after it, the procedure is in exactly the state
// after the last record. Throws SessionLogError when a record is not what the procedure would have presented.
void replay(Procedure& procedure, const std::vector<TrialRecord>& records);
// Both of the above.
std::unique_ptr<Procedure> resume(const SessionLogContents& log);

// Appends records, each written whole and fsync'ed before append() returns.
class SessionLogWriter {
 public:
  // A new log; refuses a file that exists (a session is never written over).
  static SessionLogWriter create(const std::string& path, const SessionHeader& h);
  // An existing log: truncated to its last complete line, then appended to.
  static SessionLogWriter resume(const std::string& path, const SessionLogContents& read);
  SessionLogWriter(SessionLogWriter&& other) noexcept;
  SessionLogWriter& operator=(SessionLogWriter&&) = delete;
  SessionLogWriter(const SessionLogWriter&) = delete;
  ~SessionLogWriter();

  void append(const TrialRecord& r);

 private:
  SessionLogWriter(int fd, std::string path) : fd_(fd), path_(std::move(path)) {}
  void write_line(const std::string& line);
  int fd_ = -1;
  std::string path_;
};

}  // namespace lever::study
