#include "snapshot_json.hpp"

#include "lever/protocol/fault_names.hpp"

namespace lever::view {
namespace {

using nlohmann::json;

template <typename T>
json or_null(const std::optional<T>& v) {
  return v ? json(*v) : json();
}

json direction(const DirectionView& d) {
  return {{"frames", d.frames}, {"per_s", d.per_second},          {"share", d.share()},       {"savings", d.savings()},
          {"lost", d.lost},     {"out_of_order", d.out_of_order}, {"refreshes", d.refreshes}, {"restarts", d.restarts}};
}

json lever(const LeverView& l) {
  const json faults = l.heard ? json(protocol::fault_name_list(l.heartbeat.faults)) : json::array();
  json out{{"heard", l.heard},
           {"heartbeat_age_s", or_null(l.heartbeat_age_s)},
           {"silent", l.silent()},
           {"state", l.heard ? json(std::string(protocol::name(l.heartbeat.state))) : json()},
           {"homed", l.heard ? json(l.heartbeat.position_valid) : json()},
           {"faults", faults},
           {"heartbeats", l.heartbeats},
           {"heartbeats_lost", l.heartbeats_lost},
           {"heartbeats_out_of_order", l.heartbeats_out_of_order},
           {"peer_seq_gaps", l.heard ? json(l.heartbeat.seq_gaps) : json()},
           {"rejected_frames", l.heard ? json(l.heartbeat.rejected_frames) : json()},
           {"energy_frames", l.energy_frames}};
  out["settings_frames"] = l.settings_frames;
  if (l.settings) {
    const auto& m = *l.settings;
    const auto c = protocol::codec_settings(m);
    out["settings"] = {{"mode", std::string(codec::name(c.mode))},
                       {"p", c.p},
                       {"floor", c.floor},
                       {"filter_hz", c.filter_hz},
                       {"changes", m.changes},
                       {"tares", m.tares},
                       {"taring", m.taring}};
  } else {
    out["settings"] = json();
  }
  if (l.status) {
    out["status"] = {{"state", l.status->state},
                     {"faults", l.status->faults},
                     {"position_rad", or_null(l.status->position_rad)},
                     {"velocity_rad_s", or_null(l.status->velocity_rad_s)},
                     {"force_n", or_null(l.status->force_n)},
                     {"torque_nm", or_null(l.status->torque_nm)},
                     {"data_sent", or_null(l.status->data_sent)},
                     {"age_s", or_null(l.status_age_s)}};
  }
  return out;
}

}  // namespace

json to_json(const Snapshot& s, const ReaderState& reader) {
  json pairs = json::array();
  for (const PairView& p : s.pairs) {
    pairs.push_back({{"pair", p.pair},
                     {"hsi", lever(p.levers[0])},
                     {"top", lever(p.levers[1])},
                     {"hsi_position_rad", or_null(p.hsi_position_rad())},
                     {"hsi_velocity_rad_s", or_null(p.hsi_velocity_rad_s())},
                     {"motion_age_s", or_null(p.motion_age_s)},
                     {"top_force_n", or_null(p.top_force_n())},
                     {"force_age_s", or_null(p.force_age_s)},
                     {"motion", direction(p.motion)},
                     {"force", direction(p.force)},
                     {"commands", p.commands}});
  }
  json bridges = json::array();
  for (const BridgeView& b : s.bridges) {
    bridges.push_back({{"source", b.source},
                       {"can", b.status.can},
                       {"bus_load", or_null(b.status.bus_load)},
                       {"to_network_per_s", or_null(b.status.to_network_per_s)},
                       {"from_network_per_s", or_null(b.status.from_network_per_s)},
                       {"sequence_gaps", b.status.sequence_gaps},
                       {"reordered", b.status.reordered},
                       {"latency_p99_us", or_null(b.status.latency_p99_us)},
                       {"age_s", b.age_s}});
  }
  return {{"t", static_cast<double>(s.now_us) * 1e-6},
          {"interface", reader.interface},
          {"link_up", reader.link_up},
          {"kernel_drops", reader.kernel_drops},
          {"bus",
           {{"frames", s.bus.frames},
            {"frames_per_s", s.bus.frames_per_s},
            {"bits_per_s", s.bus.bits_per_s},
            {"load", s.bus.load},
            {"unknown_ids", s.bus.unknown_ids},
            {"rejected", s.bus.rejected}}},
          {"pairs", pairs},
          {"bridges", bridges},
          {"status_lines", s.status_lines}};
}

}  // namespace lever::view
