#include "serve_report.hpp"

#include <fmt/format.h>

#include "lever/app/stats_line.hpp"
#include "lever/protocol/fault_names.hpp"
#include "report.hpp"

namespace lever::hil {
namespace {

std::string faults_text(const WatchedLever& l) {
  if (!l.heartbeat || l.heartbeat->faults == 0) return "";
  return " [" + protocol::fault_names(l.heartbeat->faults, "+") + "]";
}

int state_number(const WatchedLever& l) { return l.heartbeat ? static_cast<int>(l.heartbeat->state) : -1; }

nlohmann::json serve_json(const ServeSummary& s, const ServeMetrics& metrics) {
  const ServeExtras& x = metrics.extras();
  return {
      {"max_position_error_rad", x.max_position_error_rad},
      {"mean_hsi_torque_in_contact_nm", metrics.mean_hsi_torque_in_contact_nm()},
      {"max_displayed_force_n", x.max_displayed_force_n},
      {"slips", s.slips},
      {"max_lag_ms", s.max_lag_ms},
      {"silent_ms", {{"hsi", x.hsi_silent_ms}, {"top", x.top_silent_ms}}},
      {"encoder_edges", {{"hsi", s.hsi_encoder.edges}, {"top", s.top_encoder.edges}}},
      {"encoder_max_backlog", {{"hsi", s.hsi_encoder.max_backlog}, {"top", s.top_encoder.max_backlog}}},
      {"gauge_requests", s.gauge_requests},
      {"can_frames_seen", s.can_frames_seen},
  };
}

void print_human(std::FILE* out, const ServeOptions& o, const ServeSummary& s, const ServeMetrics& metrics) {
  const SimResult& r = s.result;
  fmt::print(out, "served {:.1f} s of {} after {:.1f} s of homing and arming\n", s.sim.duration_s, name(o.scenario),
             r.homed_at_s);
  fmt::print(out, "  packets: velocity {:.1f} %, force {:.1f} % of 1 kHz (while both armed: {:.1f} s)\n",
             100 * r.velocity_packet_rate, 100 * r.force_packet_rate, 1e-3 * static_cast<double>(r.armed_ticks));
  fmt::print(out,
             "  position rmse {:.2f} mrad (max {:.2f}), force rmse {:.3f} N, force off by more than a JND {:.1f} %\n",
             1000 * r.position_rmse_rad, 1000 * metrics.extras().max_position_error_rad, r.force_rmse_n,
             100 * r.force_jnd_violation);
  fmt::print(out,
             "  in contact {:.0f} % of the time at {:.2f} N on average; the world slipped {} times (max lag {} ms)\n",
             100 * r.contact_share, r.mean_contact_force_n, s.slips, s.max_lag_ms);
}

}  // namespace

std::string state_name(const WatchedLever& l) {
  return l.heartbeat ? std::string(protocol::name(l.heartbeat->state)) : "silent";
}

void print_status_line(double t, const BusWatch& watch, const World& world, const ServeTick& s, double displayed,
                       const RunMetrics& metrics, std::int64_t max_lag_ms) {
  fmt::print(stderr,
             "t={:6.1f} s  HSI {}{} {:+.3f} rad {:+.3f} N m | TOP {}{} {:+.3f} rad {:+.3f} N m  contact {:5.2f} N "
             "shown {:5.2f} N  frames motion {} force {}  lag {} ms\n",
             t, state_name(watch.hsi()), faults_text(watch.hsi()), world.hsi().angle(), s.hsi_command.torque_nm,
             state_name(watch.top()), faults_text(watch.top()), world.top().angle(), s.top_command.torque_nm, s.contact,
             displayed, metrics.motion_frames(), metrics.force_frames(), max_lag_ms);
}

TraceRow serve_trace_row(double t, const World& world, const BusWatch& watch, const ServeTick& s, double displayed,
                         std::uint64_t motion_sent, std::uint64_t force_sent) {
  return {t,
          world.hsi().angle(),
          world.top().angle(),
          world.hsi().speed(),
          watch.position_sent().value_or(0.0),
          s.contact,
          s.measured,
          displayed,
          s.hsi_command.enable ? s.hsi_command.torque_nm : 0.0,
          s.top_command.enable ? s.top_command.torque_nm : 0.0,
          s.hand,
          static_cast<int>(motion_sent),
          static_cast<int>(force_sent),
          state_number(watch.hsi()),
          state_number(watch.top())};
}

void print_serve_report(const ServeOptions& o, const ServeSummary& summary, const ServeMetrics& metrics,
                        const ServeProbe* probe, std::FILE* out) {
  if (o.json) {
    auto report = report_json(summary.sim, summary.result);
    report["serve"] = serve_json(summary, metrics);
    if (probe) probe->report(report);
    fmt::print(out, "{}\n", report.dump());
  } else {
    print_human(out, o, summary, metrics);
    if (probe) {
      nlohmann::json measured;
      probe->report(measured);
      fmt::print(out, "  probe: {}\n", measured.dump());
    }
  }
}

}  // namespace lever::hil
