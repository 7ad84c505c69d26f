#include "session.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <tuple>

#include "lever/codec/receiver.hpp"
#include "lever/program/exit_codes.hpp"
#include "lever/program/text.hpp"
#include "lever/protocol/fault_names.hpp"
#include "lever/protocol/messages.hpp"

namespace lever::plot {
namespace {

namespace proto = lever::protocol;
constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
// Longer is no session: its timeline (every 10 ms) would take gigabytes.
constexpr double kMaxSpan = 86400.0;

// "force: predictive p 0.1000 floor 0.050 N filter 30.0 Hz (changes 2, tares 1)": a lever's settings frame, read.
std::string settings_text(const proto::SettingsMessage& m, bool top) {
  const auto c = proto::codec_settings(m);
  std::string filter = m.filter_hz == 0 ? "off" : fmt::format("{:.1f} Hz", c.filter_hz);
  return fmt::format("{}: {} p {:.4f} floor {:.3f} {} filter {} (changes {}, tares {}{})", top ? "force" : "motion",
                     codec::name(c.mode), c.p, c.floor, top ? "N" : "rad/s", filter, m.changes, m.tares,
                     m.taring ? ", taring" : "");
}

std::string num(double v) { return std::isnan(v) ? "" : fmt::format("{:.6g}", v); }
std::string num(int v) { return v < 0 ? "" : fmt::format("{}", v); }

const char* kFramesHeader =
    "t,iface,message,pair,role,position_rad,velocity_rad_s,force_n,energy_j,tick,seq,refresh,restart,predictive,"
    "state,position_valid,faults,seq_gaps,rejected_frames,counter,opcode,p,floor,filter_hz,changes,tares,taring\n";

// The timeline and the rate bins, filled as the frames go by: each row holds the state after every frame
// before its time.
// A candump log read into a session, frame by frame: the timeline and rate bins (as the frames' values are held
// between them), frames.csv, the counts, and what places each lever's status lines on the log's time axis.
struct LogReader {
  Session& s;
  std::uint8_t pair;
  TimelineRow current;
  double next_row = 0.0;
  codec::DeadbandReceiver<double, 1> force_receiver;
  bool force_heard = false;

  LogReader(Session& session, std::uint8_t pair_) : s(session), pair(pair_) {
    current.hsi_position = current.top_position = current.tracking_error = kNone;
    current.measured_force = current.displayed_force = kNone;
  }

  void rows_until(double t) {  // t since the session's start
    while (next_row <= t) {
      TimelineRow row = current;
      row.t = next_row;
      if (force_heard) row.displayed_force = force_receiver.reconstruct(s.t0 + next_row).value()[0];
      s.timeline.push_back(row);
      current.measured_force = current.top_position = current.tracking_error = kNone;  // points, not held
      next_row = static_cast<double>(s.timeline.size()) * kTimelineStep;
    }
  }

  RateBin& bin(double t) {
    const auto index = static_cast<std::size_t>(t / kRateBin);
    while (s.rates.size() <= index) {
      RateBin b;
      b.t = static_cast<double>(s.rates.size()) * kRateBin;
      b.motion_refresh = b.force_refresh = 0;
      s.rates.push_back(b);
    }
    return s.rates[index];
  }

  // Per lever (0 the HSI, 1 the TOP): its faults and settings as last shown; its frames' times in order (the n-th is
  // where its status line with tx_frames = n was, at the latest, printed) and how many data and refresh frames it
  // had sent by each.
  std::array<std::uint16_t, 2> faults{};
  std::array<bool, 2> heard{};
  std::array<std::string, 2> settings;
  std::array<std::vector<double>, 2> sent_at;
  std::array<std::vector<std::pair<std::uint32_t, std::uint32_t>>, 2> data_by;
  std::array<std::pair<std::uint32_t, std::uint32_t>, 2> data_count{};

  // One frame decoded: the rest of its frames.csv row (after "t,iface,message,pair,") and who sent it (0 HSI,
  // 1 TOP, -1 a host), or the decoding error.
  struct Decoded {
    proto::DecodeError error = proto::DecodeError::none;
    std::string row;
    int sender = -1;
  };
  static int sender_of(const proto::FrameAddress& a) { return a.role == proto::Role::top ? 1 : 0; }
  static Decoded failed(proto::DecodeError e) {
    Decoded d;
    d.error = e;
    return d;
  }

  Decoded motion(const proto::CanFrame& frame, proto::FrameAddress a, double t) {
    proto::MotionMessage m;
    if (const auto e = proto::decode(frame, m, a); e != proto::DecodeError::none) return failed(e);
    const double position = m.position * proto::kPositionLsbRad;
    current.hsi_position = position;
    auto& r = bin(t);
    ++r.motion;
    if (m.flags.refresh) ++r.motion_refresh, ++s.motion_refresh, ++data_count[0].second;
    ++data_count[0].first;
    return {proto::DecodeError::none,
            fmt::format("hsi,{:.6g},{:.6g},,,{},{},{:d},{:d},{:d},,,,,,,,,,,,,\n", position,
                        m.velocity * proto::kVelocityLsb, m.tick, m.seq, m.flags.refresh, m.flags.restart,
                        m.flags.mode == codec::Mode::predictive),
            0};
  }

  Decoded force(const proto::CanFrame& frame, proto::FrameAddress a, double t, double log_t) {
    proto::ForceMessage m;
    if (const auto e = proto::decode(frame, m, a); e != proto::DecodeError::none) return failed(e);
    const double value = m.force * proto::kForceLsb;
    if (m.flags.restart) force_receiver.reset();
    force_receiver.set_mode(m.flags.mode);
    force_receiver.receive(log_t, {value});
    force_heard = true;
    current.measured_force = value;
    auto& r = bin(t);
    ++r.force;
    if (m.flags.refresh) ++r.force_refresh, ++s.force_refresh, ++data_count[1].second;
    ++data_count[1].first;
    return {proto::DecodeError::none,
            fmt::format("top,,,{:.6g},,{},{},{:d},{:d},{:d},,,,,,,,,,,,,\n", value, m.tick, m.seq, m.flags.refresh,
                        m.flags.restart, m.flags.mode == codec::Mode::predictive),
            1};
  }

  static Decoded energy(const proto::CanFrame& frame, proto::FrameAddress a) {
    proto::EnergyMessage m;
    if (const auto e = proto::decode(frame, m, a); e != proto::DecodeError::none) return failed(e);
    const int sender = sender_of(a);
    return {proto::DecodeError::none,
            fmt::format("{},,,,{:.6f},{},,,,,,,,,,,,,,,,,\n", sender ? "top" : "hsi", m.energy * proto::kEnergyLsbJ,
                        m.tick),
            sender};
  }

  Decoded heartbeat(const proto::CanFrame& frame, proto::FrameAddress a, double t) {
    proto::HeartbeatMessage m;
    if (const auto e = proto::decode(frame, m, a); e != proto::DecodeError::none) return failed(e);
    const int sender = sender_of(a);
    (sender ? current.top_state : current.hsi_state) = static_cast<int>(m.state);
    (sender ? current.top_faults : current.hsi_faults) = std::popcount(m.faults);
    if (!heard[sender] || faults[sender] != m.faults) {
      if (m.faults != 0 || heard[sender])
        s.faults_seen.push_back(fmt::format("{:.3f} s {} {}", t, sender ? "TOP" : "HSI",
                                            m.faults ? proto::fault_names(m.faults, "|") : "cleared"));
      faults[sender] = m.faults;
      heard[sender] = true;
    }
    return {proto::DecodeError::none,
            fmt::format("{},,,,,,,,,,{},{:d},{},{},{},{},,,,,,,\n", sender ? "top" : "hsi", static_cast<int>(m.state),
                        m.position_valid, proto::fault_names(m.faults, "|"), m.seq_gaps, m.rejected_frames, m.counter),
            sender};
  }

  Decoded settings_frame(const proto::CanFrame& frame, proto::FrameAddress a, double t) {
    proto::SettingsMessage m;
    if (const auto e = proto::decode(frame, m, a); e != proto::DecodeError::none) return failed(e);
    const int sender = sender_of(a);
    const std::string shown = settings_text(m, sender == 1);
    if (shown != settings[sender]) {
      s.settings_seen.push_back(fmt::format("{:.3f} s {} {}", t, sender ? "TOP" : "HSI", shown));
      settings[sender] = shown;
    }
    const auto c = proto::codec_settings(m);
    return {proto::DecodeError::none,
            fmt::format("{},,,,,,,,,{:d},,,,,,,,{:.4f},{:.3f},{:.1f},{},{},{:d}\n", sender ? "top" : "hsi",
                        c.mode == codec::Mode::predictive, c.p, c.floor, c.filter_hz, m.changes, m.tares, m.taring),
            sender};
  }

  static Decoded command(const proto::CanFrame& frame, proto::FrameAddress a) {
    proto::CommandMessage m;
    if (const auto e = proto::decode(frame, m, a); e != proto::DecodeError::none) return failed(e);
    return {proto::DecodeError::none, fmt::format("host,,,,,,,,,,,,,,,,{},,,,,,\n", static_cast<int>(m.opcode)), -1};
  }

  Decoded decode(const LoggedFrame& lf, const proto::FrameAddress& a, double t) {
    switch (a.kind) {
      case proto::MessageKind::motion:
        return motion(lf.frame, a, t);
      case proto::MessageKind::force:
        return force(lf.frame, a, t, lf.t);
      case proto::MessageKind::energy:
        return energy(lf.frame, a);
      case proto::MessageKind::heartbeat:
        return heartbeat(lf.frame, a, t);
      case proto::MessageKind::settings:
        return settings_frame(lf.frame, a, t);
      case proto::MessageKind::command:
        return command(lf.frame, a);
    }
    return failed(proto::DecodeError::unknown_id);
  }

  void read(const LoggedFrame& lf) {
    // A log's clock that stepped back before the first frame's time: the frame is counted, drawn at the start.
    const double t = std::max(lf.t - s.t0, 0.0);
    rows_until(t);
    proto::FrameAddress a;
    if (proto::classify(lf.frame.id, a) != proto::DecodeError::none || a.pair != pair) {
      ++s.other_frames;
      return;
    }
    const Decoded d = decode(lf, a, t);
    if (d.error != proto::DecodeError::none) {
      ++s.decode_errors;
      return;
    }
    const std::string name(proto::message_name(a));
    ++s.counts[name];
    s.frames_csv += fmt::format("{:.6f},{},{},{},", t, lf.iface, name, a.pair) + d.row;
    if (d.sender < 0) return;
    const auto lever = static_cast<std::size_t>(d.sender);
    ++s.sent_by[lever];
    sent_at[lever].push_back(t);
    data_by[lever].push_back(data_count[lever]);
  }

  // The status lines on the time axis, and the TOP's position beside the HSI's at that time.
  void place(std::vector<StatusLine>& status) {
    for (auto& line : status) {
      const auto& at = sent_at[line.top ? 1 : 0];
      if (line.tx_frames == 0 || line.tx_frames > at.size()) continue;
      const auto sent = static_cast<std::size_t>(line.tx_frames - 1);  // below at.size(): checked above
      line.t = at[sent];
      std::tie(line.data_in_log, line.refresh_in_log) = data_by[line.top ? 1 : 0][sent];
      if (!line.top) continue;
      const auto row = static_cast<std::size_t>(std::ceil(line.t / kTimelineStep));
      if (row >= s.timeline.size()) continue;
      auto& r = s.timeline[row];
      r.top_position = line.position_rad;
      if (!std::isnan(r.hsi_position)) r.tracking_error = r.hsi_position - line.position_rad;
    }
  }
};

}  // namespace

StatusLine parse_status_line(const std::string& line, const std::string& where) {
  StatusLine s;
  try {
    const auto j = nlohmann::json::parse(line);
    const std::string role = j.at("role").get<std::string>();
    if (role != "hsi" && role != "top") throw std::invalid_argument("role must be hsi or top");
    s.top = role == "top";
    s.state = j.at("state").get<std::string>();
    s.position_rad = j.at("position_rad").get<double>();
    s.tx_frames = j.at("tx_frames").get<std::uint64_t>();
    s.data_sent = j.at("data_sent").get<std::uint64_t>();
    s.refresh_sent = j.at("refresh_sent").get<std::uint64_t>();
    s.faults = j.at("faults").get<std::vector<std::string>>();
  } catch (const std::exception& e) {
    throw program::BadInput(
        fmt::format("{}: not a lever-fw --stats-json line: {}", where, program::printable(e.what(), 120)));
  }
  s.t = kNone;
  return s;
}

Session session_from_log(const CandumpLog& log, std::uint8_t pair, const std::vector<StatusLine>& status) {
  Session s;
  s.source = "candump";
  s.frames_csv = kFramesHeader;
  if (log.frames.empty()) return s;
  s.t0 = log.frames.front().t;
  for (const auto& lf : log.frames)
    if (lf.t - s.t0 > kMaxSpan)
      throw program::BadInput(
          fmt::format("a frame at {:.6f} is {:.0f} s after the first: a recording of more than a "
                      "day (or a clock that jumped); cut it to the session first",
                      lf.t, lf.t - s.t0));
  LogReader reader(s, pair);
  for (const auto& lf : log.frames) reader.read(lf);
  s.duration = log.frames.back().t - s.t0;
  reader.rows_until(s.duration);
  reader.bin(s.duration);  // the rates to the log's end: a quiet tail, or a pair that sent no data, is 0 frames/s
  s.status = status;
  reader.place(s.status);
  return s;
}

Session session_from_hil_trace(std::istream& in, const std::string& name) {
  Session s;
  s.source = "hil";
  std::string line;
  if (!std::getline(in, line)) throw program::BadInput(fmt::format("{}: empty", name));
  std::map<std::string, std::size_t> col;
  {
    std::stringstream header(line);
    std::string c;
    for (std::size_t i = 0; std::getline(header, c, ','); ++i) col[c] = i;
  }
  const char* needed[] = {"t",           "hsi_angle",  "top_angle", "measured_force", "displayed_force",
                          "motion_sent", "force_sent", "hsi_state", "top_state"};
  for (const char* c : needed)
    if (!col.contains(c))
      throw program::BadInput(fmt::format("{}: no column {} (not a lever-hil run --trace file)", name, c));
  std::vector<double> v(col.size());
  std::size_t number = 1;
  double next_row = 0.0;
  RateBin* bin = nullptr;
  while (std::getline(in, line)) {
    ++number;
    std::stringstream fields(line);
    std::string f;
    std::size_t i = 0;
    for (; i < v.size() && std::getline(fields, f, ','); ++i) {
      char* end = nullptr;
      v[i] = std::strtod(f.c_str(), &end);
      if (f.empty() || *end != '\0' || !std::isfinite(v[i]))
        throw program::BadInput(fmt::format("{}:{}: column {} is no number", name, number, i + 1));
    }
    if (i != v.size()) throw program::BadInput(fmt::format("{}:{}: {} columns, not {}", name, number, i, v.size()));
    if (number == 2) s.t0 = v[col["t"]];
    const double t = v[col["t"]] - s.t0;
    if (t < 0 || t > kMaxSpan)
      throw program::BadInput(
          fmt::format("{}:{}: t {} is not within a day after the first row's", name, number, v[col["t"]]));
    const auto bin_index = static_cast<std::size_t>(t / kRateBin);
    while (s.rates.size() <= bin_index) {
      RateBin b;
      b.t = static_cast<double>(s.rates.size()) * kRateBin;
      s.rates.push_back(b);
    }
    bin = &s.rates[bin_index];
    bin->motion += static_cast<int>(v[col["motion_sent"]]);
    bin->force += static_cast<int>(v[col["force_sent"]]);
    s.duration = t;
    if (t + 1e-9 < next_row) continue;
    TimelineRow r;
    r.t = t;
    r.hsi_position = v[col["hsi_angle"]];
    r.top_position = v[col["top_angle"]];
    r.tracking_error = r.hsi_position - r.top_position;
    r.measured_force = v[col["measured_force"]];
    r.displayed_force = v[col["displayed_force"]];
    r.hsi_state = static_cast<int>(v[col["hsi_state"]]);
    r.top_state = static_cast<int>(v[col["top_state"]]);
    s.timeline.push_back(r);
    next_row = static_cast<double>(s.timeline.size()) * kTimelineStep;
  }
  if (s.timeline.empty()) throw program::BadInput(fmt::format("{}: a header and no rows", name));
  return s;
}

std::string timeline_csv(const Session& s) {
  std::string out =
      "t,hsi_position,top_position,tracking_error,measured_force,displayed_force,hsi_state,top_state,hsi_faults,"
      "top_faults\n";
  for (const auto& r : s.timeline)
    out += fmt::format("{:.3f},{},{},{},{},{},{},{},{},{}\n", r.t, num(r.hsi_position), num(r.top_position),
                       num(r.tracking_error), num(r.measured_force), num(r.displayed_force), num(r.hsi_state),
                       num(r.top_state), num(r.hsi_faults), num(r.top_faults));
  return out;
}

std::string rates_csv(const Session& s) {
  std::string out = "t,motion_per_s,motion_deadband_per_s,force_per_s,force_deadband_per_s\n";
  for (const auto& b : s.rates) {
    auto per_s = [](int n) { return fmt::format("{:.6g}", n / kRateBin); };
    auto deadband = [&](int all, int refresh) { return refresh < 0 ? std::string() : per_s(all - refresh); };
    out += fmt::format("{:.3f},{},{},{},{}\n", b.t, per_s(b.motion), deadband(b.motion, b.motion_refresh),
                       per_s(b.force), deadband(b.force, b.force_refresh));
  }
  return out;
}

}  // namespace lever::plot
