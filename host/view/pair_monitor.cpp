#include "pair_monitor.hpp"

#include "lever/protocol/can_timing.hpp"

namespace lever::view {
namespace {

using protocol::Role;

constexpr std::size_t index(Role role) noexcept { return static_cast<std::size_t>(role); }

std::optional<double> age_s(bool known, std::int64_t then_us, std::int64_t now_us) noexcept {
  if (!known) return std::nullopt;
  const std::int64_t age = now_us - then_us;
  return static_cast<double>(age > 0 ? age : 0) * 1e-6;
}

std::vector<std::optional<float>> to_vector(const History& h) {
  std::vector<std::optional<float>> out(h.size());
  for (std::size_t i = 0; i < h.size(); ++i) out[i] = h[i];
  return out;
}

}  // namespace

std::optional<double> PairView::hsi_position_rad() const noexcept {
  if (!motion_message) return std::nullopt;
  return motion_message->position * protocol::kPositionLsbRad;
}
std::optional<double> PairView::hsi_velocity_rad_s() const noexcept {
  if (!motion_message) return std::nullopt;
  return motion_message->velocity * protocol::kVelocityLsb;
}
std::optional<double> PairView::top_force_n() const noexcept {
  if (!force_message) return std::nullopt;
  return force_message->force * protocol::kForceLsb;
}

PairMonitor::PairMonitor(MonitorConfig config) : config_(config) {}

void PairMonitor::on_frame(const protocol::CanFrame& frame, std::int64_t t_us) noexcept {
  sample_histories(t_us);
  ++bus_.frames;
  bus_frames_.add(t_us);
  bus_bits_.add(t_us, static_cast<std::uint64_t>(protocol::frame_bits_worst_case(frame.dlc)));

  protocol::FrameAddress address;
  if (protocol::classify(frame.id, address) != protocol::DecodeError::none) {
    ++bus_.unknown_ids;
    return;
  }
  if (!shown(address.pair)) return;
  Pair& p = pairs_[address.pair];
  const auto rejected = [this](protocol::DecodeError e) {
    if (e == protocol::DecodeError::none) return false;
    ++bus_.rejected;
    return true;
  };
  switch (address.kind) {
    case protocol::MessageKind::motion: {
      protocol::MotionMessage m;
      if (rejected(protocol::decode(frame, m, address))) return;
      on_data(p.motion, m.flags, m.seq, t_us);
      p.motion_message = m;
      p.motion_us = t_us;
      break;
    }
    case protocol::MessageKind::force: {
      protocol::ForceMessage m;
      if (rejected(protocol::decode(frame, m, address))) return;
      on_data(p.force, m.flags, m.seq, t_us);
      p.force_message = m;
      p.force_us = t_us;
      break;
    }
    case protocol::MessageKind::energy: {
      protocol::EnergyMessage m;
      if (rejected(protocol::decode(frame, m, address))) return;
      ++p.levers[index(address.role)].energy_frames;
      break;
    }
    case protocol::MessageKind::settings: {
      protocol::SettingsMessage m;
      if (rejected(protocol::decode(frame, m, address))) return;
      Lever& lever = p.levers[index(address.role)];
      lever.settings = m;
      ++lever.settings_frames;
      break;
    }
    case protocol::MessageKind::heartbeat: {
      protocol::HeartbeatMessage m;
      if (rejected(protocol::decode(frame, m, address))) return;
      Lever& lever = p.levers[index(address.role)];
      lever.heard = true;
      lever.heartbeat = m;
      lever.heartbeat_us = t_us;
      ++lever.heartbeats;
      lever.counter.on(m.counter);
      break;
    }
    case protocol::MessageKind::command: {
      protocol::CommandMessage m;
      if (rejected(protocol::decode(frame, m, address))) return;
      ++p.commands;
      p.last_command = m.opcode;
      break;
    }
  }
  p.seen = true;
}

void PairMonitor::on_data(Direction& d, const protocol::DataFlags& flags, std::uint8_t seq,
                          std::int64_t t_us) noexcept {
  if (flags.restart) {
    d.seq.restart();
    ++d.counts.restarts;
  }
  d.seq.on(seq);
  ++d.counts.frames;
  if (flags.refresh) ++d.counts.refreshes;
  d.rate.add(t_us);
}

void PairMonitor::on_status(const StatusLine& line, std::size_t source, std::int64_t t_us) {
  if (const auto* lever = std::get_if<LeverStatus>(&line)) {
    if (!shown(lever->pair)) return;
    sample_histories(t_us);
    Pair& p = pairs_[lever->pair];
    p.seen = true;
    p.levers[index(lever->role)].status = *lever;
    p.levers[index(lever->role)].status_us = t_us;
    ++status_lines_;
  } else if (const auto* bridge = std::get_if<BridgeStatus>(&line)) {
    if (bridges_.size() <= source) bridges_.resize(source + 1);
    bridges_[source] = std::pair{*bridge, t_us};
    ++status_lines_;
  }
}

void PairMonitor::sample_histories(std::int64_t t_us) noexcept {
  if (!next_sample_us_) {
    next_sample_us_ = t_us - t_us % kHistoryPeriodUs + kHistoryPeriodUs;
    return;
  }
  // A long silence (or a clock set forward) fills at most one history's worth of empty samples.
  if (t_us - *next_sample_us_ > static_cast<std::int64_t>(History::kCapacity) * kHistoryPeriodUs)
    *next_sample_us_ = t_us - static_cast<std::int64_t>(History::kCapacity) * kHistoryPeriodUs;
  for (; *next_sample_us_ <= t_us; *next_sample_us_ += kHistoryPeriodUs) {
    const std::int64_t at = *next_sample_us_;
    for (Pair& p : pairs_) {
      if (!p.seen) continue;
      const auto fresh = [at](bool known, std::int64_t then, std::int64_t limit) {
        return known && at - then <= limit;
      };
      p.hsi_position.push(
          fresh(p.motion_message.has_value(), p.motion_us, kStaleAfterUs)
              ? std::optional<float>(static_cast<float>(p.motion_message->position * protocol::kPositionLsbRad))
              : std::nullopt);
      p.top_force.push(fresh(p.force_message.has_value(), p.force_us, kStaleAfterUs)
                           ? std::optional<float>(static_cast<float>(p.force_message->force * protocol::kForceLsb))
                           : std::nullopt);
      // Status lines come once a second: one is current for two seconds.
      const Lever& top = p.levers[index(Role::top)];
      p.top_position.push(fresh(top.status && top.status->position_rad, top.status_us, 2'000'000)
                              ? std::optional<float>(static_cast<float>(*top.status->position_rad))
                              : std::nullopt);
    }
  }
}

void PairMonitor::reset() noexcept {
  bus_ = BusView{};
  bus_frames_.reset();
  bus_bits_.reset();
  for (Pair& p : pairs_) {
    for (Lever& lever : p.levers) {
      lever.heartbeats = 0;
      lever.counter.reset();
      lever.energy_frames = 0;
      lever.settings_frames = 0;
    }
    for (Direction* d : {&p.motion, &p.force}) *d = Direction{};
    p.commands = 0;
    p.hsi_position.clear();
    p.top_force.clear();
    p.top_position.clear();
  }
  status_lines_ = 0;
}

Snapshot PairMonitor::snapshot(std::int64_t now_us) {
  sample_histories(now_us);
  Snapshot s;
  s.now_us = now_us;
  s.bus = bus_;
  s.bus.frames_per_s = static_cast<double>(bus_frames_.last_second(now_us));
  s.bus.bits_per_s = static_cast<double>(bus_bits_.last_second(now_us));
  s.bus.load = s.bus.bits_per_s / config_.bitrate;
  s.status_lines = status_lines_;
  for (std::size_t n = 0; n < pairs_.size(); ++n) {
    const Pair& p = pairs_[n];
    if (!p.seen) continue;
    PairView v;
    v.pair = static_cast<std::uint8_t>(n);
    for (std::size_t r = 0; r < 2; ++r) {
      const Lever& lever = p.levers[r];
      LeverView& out = v.levers[r];
      out.heard = lever.heard;
      out.heartbeat_age_s = age_s(lever.heard, lever.heartbeat_us, now_us);
      out.heartbeat = lever.heartbeat;
      out.heartbeats = lever.heartbeats;
      out.heartbeats_lost = lever.counter.lost();
      out.heartbeats_out_of_order = lever.counter.out_of_order();
      out.energy_frames = lever.energy_frames;
      out.settings = lever.settings;
      out.settings_frames = lever.settings_frames;
      out.status = lever.status;
      out.status_age_s = age_s(lever.status.has_value(), lever.status_us, now_us);
    }
    const auto direction = [now_us](const Direction& d) {
      DirectionView out = d.counts;
      out.lost = d.seq.lost();
      out.out_of_order = d.seq.out_of_order();
      out.per_second = static_cast<double>(d.rate.last_second(now_us));
      return out;
    };
    v.motion = direction(p.motion);
    v.force = direction(p.force);
    v.motion_message = p.motion_message;
    v.motion_age_s = age_s(p.motion_message.has_value(), p.motion_us, now_us);
    v.force_message = p.force_message;
    v.force_age_s = age_s(p.force_message.has_value(), p.force_us, now_us);
    v.commands = p.commands;
    v.last_command = p.last_command;
    v.hsi_position_history = to_vector(p.hsi_position);
    v.top_force_history = to_vector(p.top_force);
    v.top_position_history = to_vector(p.top_position);
    s.pairs.push_back(std::move(v));
  }
  for (std::size_t i = 0; i < bridges_.size(); ++i) {
    if (!bridges_[i]) continue;
    s.bridges.push_back({i, bridges_[i]->first, static_cast<double>(now_us - bridges_[i]->second) * 1e-6});
  }
  return s;
}

}  // namespace lever::view
