#include "lever/study/pair_watch.hpp"

#include <fmt/format.h>

#include "lever/protocol/fault_names.hpp"

namespace lever::study {

const char* role_name(protocol::Role r) noexcept { return r == protocol::Role::hsi ? "HSI" : "TOP"; }

void PairWatch::on_frame(const protocol::CanFrame& frame, std::int64_t t_us) noexcept {
  protocol::FrameAddress address;
  if (protocol::classify(frame.id, address) != protocol::DecodeError::none || address.pair != pair_) return;
  if (t_us > newest_us_) newest_us_ = t_us;
  switch (address.kind) {
    case protocol::MessageKind::motion:
      ++data_[static_cast<std::size_t>(protocol::Direction::motion)];
      break;
    case protocol::MessageKind::force:
      ++data_[static_cast<std::size_t>(protocol::Direction::force)];
      break;
    case protocol::MessageKind::heartbeat: {
      protocol::HeartbeatMessage m;
      if (protocol::decode(frame, m, address) != protocol::DecodeError::none) return;
      auto& seen = levers_[static_cast<std::size_t>(address.role)];
      seen.heartbeat = m;
      seen.heartbeat_us = t_us;
      break;
    }
    case protocol::MessageKind::settings: {
      protocol::SettingsMessage m;
      if (protocol::decode(frame, m, address) != protocol::DecodeError::none) return;
      auto& seen = levers_[static_cast<std::size_t>(address.role)];
      seen.settings = m;
      seen.settings_us = t_us;
      break;
    }
    default:
      break;
  }
}

std::string PairWatch::not_ready(std::int64_t now_us) const {
  std::string why;
  for (const auto role : {protocol::Role::hsi, protocol::Role::top}) {
    const auto& seen = lever(role);
    std::string lever_why;
    if (!seen.heartbeat || now_us - seen.heartbeat_us > kHeartbeatFreshUs) {
      lever_why = seen.heartbeat
                      ? fmt::format("no heartbeat for {:.1f} s", static_cast<double>(now_us - seen.heartbeat_us) / 1e6)
                      : "no heartbeat heard";
    } else {
      const auto& h = *seen.heartbeat;
      if (h.state != protocol::LeverState::armed) lever_why = fmt::format("{}", protocol::name(h.state));
      if (!h.position_valid) lever_why += lever_why.empty() ? "not homed" : ", not homed";
      if (h.faults != 0)
        lever_why += fmt::format("{}faults {}", lever_why.empty() ? "" : ", ", protocol::fault_names(h.faults, ", "));
    }
    if (!lever_why.empty()) why += fmt::format("{}{}: {}", why.empty() ? "" : "; ", role_name(role), lever_why);
  }
  return why;
}

protocol::SettingsMessage settings_for(const Interval& interval, protocol::Direction d,
                                       const protocol::SettingsMessage& baseline) noexcept {
  protocol::SettingsMessage s = baseline;
  codec::Config<double> c = protocol::codec_settings(baseline);
  c.p = d == protocol::Direction::motion ? interval.p_velocity : interval.p_force;
  protocol::set_codec_settings(s, c);
  return s;
}

protocol::CommandMessage command_for(protocol::Direction d, const protocol::SettingsMessage& wanted) noexcept {
  protocol::CommandMessage m;
  m.opcode = protocol::Opcode::set_deadband;
  m.to_hsi = sender_of(d) == protocol::Role::hsi;
  m.to_top = !m.to_hsi;
  m.direction = d;
  protocol::set_codec_settings(m, protocol::codec_settings(wanted));
  return m;
}

bool confirms(const protocol::SettingsMessage& seen, std::uint8_t changes_before,
              const protocol::SettingsMessage& wanted) noexcept {
  return seen.changes != changes_before && protocol::same_codec_settings(seen, wanted);
}

nlohmann::json settings_json(const protocol::SettingsMessage& s, std::int64_t at_us) {
  const auto c = protocol::codec_settings(s);
  return {{"mode", std::string(codec::name(c.mode))},
          {"p", c.p},
          {"floor", c.floor},
          {"filter_hz", c.filter_hz},
          {"changes", s.changes},
          {"at_bus_us", at_us}};
}

std::string describe(const protocol::SettingsMessage& s) {
  const auto c = protocol::codec_settings(s);
  const std::string filter =
      s.filter_hz == 0 ? std::string("prefilter off") : fmt::format("prefilter {:.1f} Hz", c.filter_hz);
  return fmt::format("p {:.2f} %, floor {:.3f}, {}, {}", c.p * 100.0, c.floor, filter, codec::name(c.mode));
}

}  // namespace lever::study
