#pragma once
// Messages with random contents for the protocol tests: every field over its whole range.
#include "lever/common/rng.hpp"
#include "lever/protocol/messages.hpp"

namespace lever::test {

inline protocol::HeartbeatMessage random_heartbeat(Rng& rng) {
  protocol::HeartbeatMessage h;
  h.state = static_cast<protocol::LeverState>(rng.next() % 5);
  h.position_valid = (rng.next() & 1) != 0;
  h.arming_parity = (rng.next() & 1) != 0;
  h.peer_arming_parity = (rng.next() & 1) != 0;
  h.peer_arming_known = (rng.next() & 1) != 0;
  h.faults = static_cast<std::uint16_t>(rng.next());
  h.last_data_seq = static_cast<std::uint8_t>(rng.next());
  h.seq_gaps = static_cast<std::uint8_t>(rng.next());
  h.rejected_frames = static_cast<std::uint8_t>(rng.next());
  h.counter = static_cast<std::uint8_t>(rng.next());
  h.encoder_errors = static_cast<std::uint8_t>(rng.next());
  return h;
}

// The counters within their 6 bits, as they come off the wire.
inline protocol::SettingsMessage random_settings(Rng& rng) {
  protocol::SettingsMessage s;
  s.mode = (rng.next() & 1) ? codec::Mode::predictive : codec::Mode::deadband;
  s.changes = static_cast<std::uint8_t>(rng.next() % protocol::kSettingsCountModulo);
  s.tares = static_cast<std::uint8_t>(rng.next() % protocol::kSettingsCountModulo);
  s.taring = (rng.next() & 1) != 0;
  s.p = static_cast<std::uint16_t>(rng.next());
  s.floor = static_cast<std::uint16_t>(rng.next());
  s.filter_hz = static_cast<std::uint16_t>(rng.next());
  return s;
}

}  // namespace lever::test
