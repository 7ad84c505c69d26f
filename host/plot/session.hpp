#pragma once
// A session as lever-plot draws it, from either source: a candump -L recording of a pair (decoded by the
// protocol's own message set) with the levers' status lines if given, or lever-hil run's per-tick trace. Both
// become the same timeline (every 10 ms) and rate bins, so one gnuplot script draws either.
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "candump_log.hpp"

namespace lever::plot {

inline constexpr double kTimelineStep = 0.01;  // s
inline constexpr double kRateBin = 0.5;        // s

struct TimelineRow {
  double t = 0.0;  // since the session's first frame or tick
  // NaN: not known at this row (no frame yet, or no status line there)
  double hsi_position = 0.0, top_position = 0.0, tracking_error = 0.0;
  double measured_force = 0.0;   // at the TOP: a force frame's value in the row it arrived (a log), every tick (HIL)
  double displayed_force = 0.0;  // at the HSI: the receiver's reconstruction from the force frames
  int hsi_state = -1, top_state = -1;    // protocol::LeverState's numbers; -1 unknown
  int hsi_faults = -1, top_faults = -1;  // latched fault bits set; -1 unknown
};

struct RateBin {
  double t = 0.0;                               // the bin's start
  int motion = 0, force = 0;                    // data frames sent in the bin
  int motion_refresh = -1, force_refresh = -1;  // of those, flagged a refresh; -1: the source does not say
};

// One lever's status line (lever-fw --stats-json), with the time the log places it at.
struct StatusLine {
  double t = 0.0;  // NaN if the log cannot place it
  bool top = false;
  std::string state;
  double position_rad = 0.0;
  std::uint64_t tx_frames = 0, data_sent = 0, refresh_sent = 0;
  std::vector<std::string> faults;
  // When placed: the lever's data and refresh frames in the log up to that time, beside data_sent and
  // refresh_sent (equal when the log holds every frame the lever sent)
  std::uint64_t data_in_log = 0, refresh_in_log = 0;
};

struct Session {
  std::string source;  // "candump" or "hil"
  double t0 = 0.0, duration = 0.0;
  std::vector<TimelineRow> timeline;
  std::vector<RateBin> rates;
  // A log only:
  std::string frames_csv;                     // one row per frame of the pair, by named columns
  std::map<std::string, std::size_t> counts;  // frames per message (the DBC's names), the pair's
  std::size_t motion_refresh = 0, force_refresh = 0;
  std::size_t other_frames = 0;          // frames of other pairs, or of ids the protocol does not define
  std::size_t decode_errors = 0;         // frames of the protocol's ids that do not decode (length, reserved values)
  std::array<std::size_t, 2> sent_by{};  // frames sent by the HSI, the TOP (heartbeats, data, energy, settings)
  std::vector<StatusLine> status;
  std::vector<std::string> faults_seen;    // "TIME ROLE fault,fault" when a lever's latched faults change
  std::vector<std::string> settings_seen;  // "TIME ROLE motion: deadband p ..." when a lever's settings frame changes
};

// The frames of `pair`; the status lines (may be empty) are placed on the log's time axis by their tx_frames
// count (the lever's own count of frames sent, matched to its frames in the log).
Session session_from_log(const CandumpLog& log, std::uint8_t pair, const std::vector<StatusLine>& status);

// lever-hil run --trace: its header names the columns (report.cpp's trace_csv_header). Throws
// program::BadInput on a trace without them.
Session session_from_hil_trace(std::istream& in, const std::string& name);

// One status line of lever-fw --stats-json; throws program::BadInput naming the file and line.
StatusLine parse_status_line(const std::string& line, const std::string& where);

std::string timeline_csv(const Session& s);
std::string rates_csv(const Session& s);

}  // namespace lever::plot
