#include "lever/study/session_log.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "lever/study/rating.hpp"
#include "lever/study/three_ifc.hpp"

namespace lever::study {
namespace {

template <typename T>
nlohmann::ordered_json or_null(const std::optional<T>& v) {
  return v ? nlohmann::ordered_json(*v) : nlohmann::ordered_json(nullptr);
}

template <typename T>
std::optional<T> optional_field(const nlohmann::json& j, const char* field) {
  if (!j.contains(field) || j.at(field).is_null()) return std::nullopt;
  return j.at(field).get<T>();
}

std::string errno_text() { return std::strerror(errno); }

}  // namespace

TrialRecord record_of(const Trial& t, int attempt) {
  TrialRecord r;
  r.attempt = attempt;
  r.kind = t.kind;
  r.pass = t.pass;
  r.trial = t.trial;
  r.p = t.p;
  r.direction = t.direction;
  r.carrier = t.carrier;
  for (const auto& i : t.intervals) r.intervals.push_back({i, {}, {}, {}, {}, nullptr});
  return r;
}

nlohmann::ordered_json to_json(const SessionHeader& h) {
  auto j = nlohmann::ordered_json{{"record", "session"},  {"format", kLogFormat}, {"protocol", h.protocol},
                                  {"subject", h.subject}, {"seed", h.seed},       {"simulated", h.simulated},
                                  {"config", h.config}};
  // Only when there is one, so the logs of pairs and of simulate-session read as they always did.
  if (!h.simulator.is_null()) j["simulator"] = h.simulator;
  return j;
}

nlohmann::ordered_json to_json(const TrialRecord& r) {
  nlohmann::ordered_json intervals = nlohmann::ordered_json::array();
  for (const auto& i : r.intervals)
    intervals.push_back({{"p_velocity", i.interval.p_velocity},
                         {"p_force", i.interval.p_force},
                         {"duration_s", i.interval.duration_s},
                         {"start_bus_us", or_null(i.start_bus_us)},
                         {"end_bus_us", or_null(i.end_bus_us)},
                         {"frames_velocity", or_null(i.frames_velocity)},
                         {"frames_force", or_null(i.frames_force)},
                         {"confirmed", i.confirmed}});
  return nlohmann::ordered_json{
      {"record", "trial"},
      {"attempt", r.attempt},
      {"kind", std::string(name(r.kind))},
      {"pass", r.pass},
      {"trial", r.trial},
      {"p", r.p},
      {"direction", std::string(name(r.direction))},
      {"carrier", r.carrier > 0 ? nlohmann::ordered_json(r.carrier) : nlohmann::ordered_json(nullptr)},
      {"answer", or_null(r.answer)},
      {"right", or_null(r.right)},
      {"void", or_null(r.void_reason)},
      {"intervals", intervals}};
}

SessionHeader header_from_json(const nlohmann::json& j) {
  if (!j.is_object() || j.value("record", "") != "session")
    throw SessionLogError("the first line is not a session header ({\"record\":\"session\", ...})");
  if (j.value("format", 0) != kLogFormat)
    throw SessionLogError(
        fmt::format("log format {} is not the one this program reads ({})", j.value("format", 0), kLogFormat));
  SessionHeader h;
  try {
    h.protocol = j.at("protocol").get<std::string>();
    h.subject = j.at("subject").get<std::string>();
    h.seed = j.at("seed").get<std::uint64_t>();
    h.simulated = j.value("simulated", false);
    h.config = j.value("config", nlohmann::json::object());
    h.simulator = j.value("simulator", nlohmann::json(nullptr));
    if (!h.simulator.is_null() && !h.simulator.is_object())
      throw SessionLogError("the session header's simulator is not an object");
  } catch (const nlohmann::json::exception& e) {
    throw SessionLogError(fmt::format("the session header: {}", e.what()));
  }
  return h;
}

TrialRecord record_from_json(const nlohmann::json& j) {
  if (!j.is_object() || j.value("record", "") != "trial") throw SessionLogError("not a trial record");
  TrialRecord r;
  try {
    r.attempt = j.at("attempt").get<int>();
    const auto kind = kind_named(j.at("kind").get<std::string>());
    const auto direction = direction_named(j.at("direction").get<std::string>());
    if (!kind || !direction) throw SessionLogError("a trial record's kind or direction is not one this program knows");
    r.kind = *kind;
    r.direction = *direction;
    r.pass = j.at("pass").get<int>();
    r.trial = j.at("trial").get<int>();
    r.p = j.at("p").get<double>();
    r.carrier = optional_field<int>(j, "carrier").value_or(0);
    r.answer = optional_field<int>(j, "answer");
    r.right = optional_field<bool>(j, "right");
    r.void_reason = optional_field<std::string>(j, "void");
    for (const auto& i : j.at("intervals")) {
      IntervalRecord ir;
      ir.interval = {i.at("p_velocity").get<double>(), i.at("p_force").get<double>(), i.at("duration_s").get<double>()};
      ir.start_bus_us = optional_field<std::int64_t>(i, "start_bus_us");
      ir.end_bus_us = optional_field<std::int64_t>(i, "end_bus_us");
      ir.frames_velocity = optional_field<std::uint64_t>(i, "frames_velocity");
      ir.frames_force = optional_field<std::uint64_t>(i, "frames_force");
      ir.confirmed = i.value("confirmed", nlohmann::json(nullptr));
      r.intervals.push_back(std::move(ir));
    }
  } catch (const nlohmann::json::exception& e) {
    throw SessionLogError(fmt::format("a trial record: {}", e.what()));
  }
  return r;
}

SessionLogContents parse_session_log(const std::string& text, const std::string& log_name) {
  SessionLogContents out;
  std::size_t start = 0;
  int line_number = 0;
  bool have_header = false;
  while (start < text.size()) {
    ++line_number;
    const std::size_t end = text.find('\n', start);
    const bool cut = end == std::string::npos;
    const std::string line = text.substr(start, cut ? std::string::npos : end - start);
    const bool last = cut || end + 1 >= text.size();
    nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    if (cut || j.is_discarded()) {
      // Only the last line can have been cut by a kill mid-write; anywhere else the log is damaged.
      if (!last) throw SessionLogError(fmt::format("{}: line {} is not JSON", log_name, line_number));
      out.warnings.push_back(fmt::format("{}: line {} ({} bytes) is {} and was ignored: cut by an interrupted write",
                                         log_name, line_number, line.size(), cut ? "without its newline" : "not JSON"));
      break;
    }
    try {
      if (!have_header) {
        out.header = header_from_json(j);
        have_header = true;
      } else {
        out.records.push_back(record_from_json(j));
      }
    } catch (const SessionLogError& e) {
      throw SessionLogError(fmt::format("{}: line {}: {}", log_name, line_number, e.what()));
    }
    out.complete_bytes = end + 1;
    start = end + 1;
  }
  if (!have_header) throw SessionLogError(fmt::format("{}: no complete session header", log_name));
  return out;
}

SessionLogContents read_session_log(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SessionLogError(fmt::format("{}: cannot be read: {}", path, errno_text()));
  std::ostringstream text;
  text << in.rdbuf();
  return parse_session_log(text.str(), path);
}

std::unique_ptr<Procedure> make_procedure(const SessionHeader& h) {
  try {
    if (h.protocol == "3ifc") return std::make_unique<ThreeIfcStaircase>(three_ifc_config_from_json(h.config), h.seed);
    if (h.protocol == "rating") return std::make_unique<RatingRun>(rating_config_from_json(h.config), h.seed);
  } catch (const std::invalid_argument& e) {
    throw SessionLogError(fmt::format("the header's config: {}", e.what()));
  }
  throw SessionLogError(fmt::format("protocol '{}' is neither 3ifc nor rating", h.protocol));
}

void replay(Procedure& procedure, const std::vector<TrialRecord>& records) {
  int attempt = 0;
  for (const auto& r : records) {
    ++attempt;
    const auto where = [&](const std::string& what) {
      return SessionLogError(fmt::format("record of attempt {}: {}", r.attempt, what));
    };
    if (r.attempt != attempt) throw where(fmt::format("attempt {} expected", attempt));
    if (procedure.done()) throw where("the procedure was over before it");
    const Trial& t = procedure.current();
    if (r.kind != t.kind || r.pass != t.pass || r.trial != t.trial || std::abs(r.p - t.p) > 1e-12 ||
        r.direction != t.direction || r.carrier != t.carrier)
      throw where(fmt::format(
          "it shows {} pass {} trial {} p {} {} carrier {}, the procedure presents {} pass {} trial {} p {} {} "
          "carrier {}: the log was not written with this config and seed",
          name(r.kind), r.pass, r.trial, r.p, name(r.direction), r.carrier, name(t.kind), t.pass, t.trial, t.p,
          name(t.direction), t.carrier));
    if (r.void_reason) {
      procedure.void_trial();
    } else if (t.takes_answer()) {
      if (!r.answer) throw where("a trial that takes an answer has none, and is not void");
      const auto outcome = procedure.answer(*r.answer);
      if (!outcome.accepted) throw where(outcome.refused);
    } else {
      procedure.acknowledge();
    }
  }
}

std::unique_ptr<Procedure> resume(const SessionLogContents& log) {
  auto procedure = make_procedure(log.header);
  replay(*procedure, log.records);
  return procedure;
}

SessionLogWriter SessionLogWriter::create(const std::string& path, const SessionHeader& h) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) throw SessionLogError(fmt::format("{}: cannot be created: {}", path, errno_text()));
  SessionLogWriter w(fd, path);
  w.write_line(to_json(h).dump());
  return w;
}

SessionLogWriter SessionLogWriter::resume(const std::string& path, const SessionLogContents& read) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) throw SessionLogError(fmt::format("{}: cannot be opened: {}", path, errno_text()));
  SessionLogWriter w(fd, path);
  // A cut last line would otherwise sit in the middle of the log once the next record follows it.
  if (::ftruncate(fd, static_cast<off_t>(read.complete_bytes)) != 0 || ::lseek(fd, 0, SEEK_END) < 0 || ::fsync(fd) != 0)
    throw SessionLogError(fmt::format("{}: cannot be cut to its last complete line: {}", path, errno_text()));
  return w;
}

SessionLogWriter::SessionLogWriter(SessionLogWriter&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), path_(std::move(other.path_)) {}

SessionLogWriter::~SessionLogWriter() {
  if (fd_ >= 0) ::close(fd_);
}

void SessionLogWriter::append(const TrialRecord& r) { write_line(to_json(r).dump()); }

void SessionLogWriter::write_line(const std::string& line) {
  const std::string text = line + "\n";
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw SessionLogError(fmt::format("{}: write failed: {}", path_, errno_text()));
    done += static_cast<std::size_t>(n);
  }
  // The answer is on disk before the next interval starts: a kill or a power cut loses at most the trial under way.
  if (::fsync(fd_) != 0) throw SessionLogError(fmt::format("{}: fsync failed: {}", path_, errno_text()));
}

}  // namespace lever::study
