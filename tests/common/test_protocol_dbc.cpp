// common/protocol/lever.dbc is the written spec: parse it here, pack with the C++ packers, decode every
// signal by the DBC's own bit layout (with an extractor written independently of bit_field.hpp), compare.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <string_view>

#include "lever/common/rng.hpp"
#include "lever/protocol/messages.hpp"
#include "random_messages.hpp"

using namespace lever::protocol;

namespace {

struct DbcSignal {
  unsigned start = 0, length = 0;
  bool little_endian = true, is_signed = false;
  double factor = 1, offset = 0, min = 0, max = 0;
  int when = -1;  // multiplexed: present only when the message's multiplexor has this value
};
struct DbcMessage {
  std::uint32_t id = 0;
  unsigned dlc = 0;
  std::map<std::string, DbcSignal> signals;
  std::string multiplexor;  // the signal marked M, if any
};

// sscanf rather than std::regex: GCC 12 reports a false -Wmaybe-uninitialized inside <regex> under ASan.
std::map<std::string, DbcMessage> parse_dbc(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  std::map<std::string, DbcMessage> out;
  DbcMessage* current = nullptr;
  std::string line;
  while (std::getline(in, line)) {
    char name[64] = {};
    unsigned id = 0, dlc = 0, start = 0, length = 0;
    char order = 0, sign = 0;
    double factor = 0, offset = 0, min = 0, max = 0;
    if (std::sscanf(line.c_str(), "BO_ %u %63[^:]: %u", &id, name, &dlc) == 3) {
      current = &out[name];
      current->id = id;
      current->dlc = dlc;
    } else if (std::sscanf(line.c_str(), " SG_ %63s : %u|%u@%c%c (%lf,%lf) [%lf|%lf]", name, &start, &length, &order,
                           &sign, &factor, &offset, &min, &max) == 9) {
      REQUIRE(current != nullptr);
      current->signals[name] = {start, length, order == '1', sign == '-', factor, offset, min, max};
    } else if (char mux[16] = {};
               std::sscanf(line.c_str(), " SG_ %63s %15s : %u|%u@%c%c (%lf,%lf) [%lf|%lf]", name, mux, &start, &length,
                           &order, &sign, &factor, &offset, &min, &max) == 10) {
      REQUIRE(current != nullptr);
      int when = -1;
      if (std::string(mux) == "M") {
        REQUIRE(current->multiplexor.empty());
        current->multiplexor = name;
      } else {
        REQUIRE(std::sscanf(mux, "m%d", &when) == 1);
      }
      current->signals[name] = {start, length, order == '1', sign == '-', factor, offset, min, max, when};
    } else {
      // No signal line goes unread (a comment on a signal, CM_ SG_, is no signal line).
      const auto first = line.find_first_not_of(" \t");
      REQUIRE((first == std::string::npos || line.compare(first, 3, "SG_") != 0));
    }
  }
  return out;
}

// Physical value of a little-endian signal, read the way a DBC tool does: bytes as one 64-bit little-endian
// integer, shift, mask, sign-extend, scale.
double dbc_value(const CanFrame& f, const DbcSignal& s) {
  REQUIRE(s.little_endian);
  std::uint64_t word = 0;
  for (int i = 7; i >= 0; --i) word = (word << 8) | f.data[i];
  std::uint64_t raw = (word >> s.start) & (s.length == 64 ? ~0ull : ((1ull << s.length) - 1));
  double value = static_cast<double>(raw);
  if (s.is_signed && (raw >> (s.length - 1)) & 1) value -= std::ldexp(1.0, static_cast<int>(s.length));
  return value * s.factor + s.offset;
}

using Expected = std::map<std::string, double>;

// The signals a frame has by the DBC: a multiplexed one only when the multiplexor has its value.
std::map<std::string, DbcSignal> present(const DbcMessage& dbc, const CanFrame& frame) {
  std::map<std::string, DbcSignal> out;
  const double selector = dbc.multiplexor.empty() ? -1 : dbc_value(frame, dbc.signals.at(dbc.multiplexor));
  for (const auto& [name, signal] : dbc.signals)
    if (signal.when < 0 || signal.when == selector) out[name] = signal;
  return out;
}

void check_frame(const DbcMessage& dbc, const CanFrame& frame, const Expected& expected) {
  CHECK(frame.id == dbc.id);
  CHECK(frame.dlc == dbc.dlc);
  const auto signals = present(dbc, frame);
  // Both sides name the same signals...
  for (const auto& entry : expected) {
    INFO(entry.first);
    CHECK(signals.count(entry.first) == 1);
  }
  for (const auto& [name, signal] : signals) {
    INFO(name);
    REQUIRE(expected.count(name) == 1);
    // ...and agree on every value, within the DBC's printed precision of the factor.
    CHECK(dbc_value(frame, signal) == Approx(expected.at(name)).margin(1e-12).epsilon(1e-12));
    CHECK(dbc_value(frame, signal) >= signal.min - 1e-9);
    CHECK(dbc_value(frame, signal) <= signal.max + 1e-9);
  }
}

}  // namespace

TEST_CASE("the C++ packers agree with lever.dbc bit for bit", "[protocol][dbc]") {
  const auto dbc = parse_dbc(LEVER_DBC_PATH);
  REQUIRE(dbc.size() == 9);
  lever::Rng rng(5);
  auto flag = [&rng] { return (rng.next() & 1) != 0; };
  for (int i = 0; i < 500; ++i) {
    MotionMessage m;
    m.position = static_cast<std::int16_t>(rng.next());
    m.velocity = static_cast<std::int16_t>(rng.next());
    m.tick = static_cast<std::uint16_t>(rng.next());
    m.seq = static_cast<std::uint8_t>(rng.next());
    m.flags = {flag(), flag(), flag(), flag() ? lever::codec::Mode::predictive : lever::codec::Mode::deadband, flag()};
    check_frame(dbc.at("LeverMotion"), pack(m, 0),
                {{"Position", m.position * kPositionLsbRad},
                 {"Velocity", m.velocity * kVelocityLsb},
                 {"Tick", m.tick},
                 {"Seq", m.seq},
                 {"PositionSaturated", m.flags.value_saturated},
                 {"VelocitySaturated", m.flags.velocity_saturated},
                 {"Refresh", m.flags.refresh},
                 {"Predictive", m.flags.mode == lever::codec::Mode::predictive},
                 {"Restart", m.flags.restart}});

    ForceMessage f;
    f.force = static_cast<std::int32_t>(rng.next() % (1u << 24)) - (1 << 23);
    f.tick = static_cast<std::uint16_t>(rng.next());
    f.seq = static_cast<std::uint8_t>(rng.next());
    f.flags = {flag(), false, flag(), flag() ? lever::codec::Mode::predictive : lever::codec::Mode::deadband, flag()};
    check_frame(dbc.at("LeverForce"), pack(f, 0),
                {{"Force", f.force * kForceLsb},
                 {"Tick", f.tick},
                 {"Seq", f.seq},
                 {"ForceSaturated", f.flags.value_saturated},
                 {"Refresh", f.flags.refresh},
                 {"Predictive", f.flags.mode == lever::codec::Mode::predictive},
                 {"Restart", f.flags.restart}});

    EnergyMessage e;
    e.energy = static_cast<std::uint32_t>(rng.next());
    e.tick = static_cast<std::uint16_t>(rng.next());
    e.epoch = static_cast<std::uint8_t>(rng.next());
    const Expected energy{{"Energy", e.energy * kEnergyLsbJ}, {"Tick", e.tick}, {"Epoch", e.epoch}};
    check_frame(dbc.at("LeverEnergyHsi"), pack(e, 0, Role::hsi), energy);
    check_frame(dbc.at("LeverEnergyTop"), pack(e, 0, Role::top), energy);

    const HeartbeatMessage h = lever::test::random_heartbeat(rng);
    const Expected heartbeat{{"State", static_cast<double>(h.state)},  {"PositionValid", h.position_valid},
                             {"ArmingParity", h.arming_parity},        {"PeerArmingParity", h.peer_arming_parity},
                             {"PeerArmingKnown", h.peer_arming_known}, {"Faults", h.faults},
                             {"LastDataSeq", h.last_data_seq},         {"SeqGaps", h.seq_gaps},
                             {"RejectedFrames", h.rejected_frames},    {"Counter", h.counter},
                             {"EncoderErrors", h.encoder_errors}};
    check_frame(dbc.at("LeverHeartbeatHsi"), pack(h, 0, Role::hsi), heartbeat);
    check_frame(dbc.at("LeverHeartbeatTop"), pack(h, 0, Role::top), heartbeat);

    const SettingsMessage st = lever::test::random_settings(rng);
    const Expected settings{{"Mode", static_cast<double>(st.mode)},
                            {"Changes", st.changes},
                            {"Tares", st.tares},
                            {"Taring", st.taring},
                            {"P", st.p * kPLsb},
                            {"Floor", st.floor * kFloorLsb},
                            {"FilterHz", st.filter_hz * kFilterHzLsb}};
    check_frame(dbc.at("LeverSettingsHsi"), pack(st, 0, Role::hsi), settings);
    check_frame(dbc.at("LeverSettingsTop"), pack(st, 0, Role::top), settings);

    CommandMessage c;
    c.opcode = static_cast<Opcode>(1 + rng.next() % 6);
    c.to_hsi = flag();
    c.to_top = flag();
    c.direction = flag() ? Direction::force : Direction::motion;
    c.mode = flag() ? lever::codec::Mode::predictive : lever::codec::Mode::deadband;
    c.p = static_cast<std::uint16_t>(rng.next());
    c.floor = static_cast<std::uint16_t>(rng.next());
    c.filter_hz = static_cast<std::uint16_t>(rng.next());
    // The payload is set_deadband's alone: the DBC multiplexes it by the opcode.
    Expected command{{"Opcode", static_cast<double>(c.opcode)}, {"ToHsi", c.to_hsi}, {"ToTop", c.to_top}};
    if (c.opcode == Opcode::set_deadband) {
      command.insert({{"Direction", static_cast<double>(c.direction)},
                      {"Mode", static_cast<double>(c.mode)},
                      {"P", c.p * kPLsb},
                      {"Floor", c.floor * kFloorLsb},
                      {"FilterHz", c.filter_hz * kFilterHzLsb}});
    }
    check_frame(dbc.at("LeverCommand"), pack(c, 0), command);
  }
}

TEST_CASE("the command frame is multiplexed by its opcode in the DBC: set_deadband's payload, nothing else's",
          "[protocol][dbc]") {
  const auto dbc = parse_dbc(LEVER_DBC_PATH);
  const auto& command = dbc.at("LeverCommand");
  CHECK(command.multiplexor == "Opcode");
  for (const char* payload : {"Direction", "Mode", "P", "Floor", "FilterHz"}) {
    INFO(payload);
    CHECK(command.signals.at(payload).when == static_cast<int>(Opcode::set_deadband));
  }
  for (const auto& [name, message] : dbc) {
    if (name == "LeverCommand") continue;
    INFO(name);
    CHECK(message.multiplexor.empty());
  }
}

TEST_CASE("the message set's table is the DBC's messages, and classify reads every id back", "[protocol][dbc]") {
  const auto dbc = parse_dbc(LEVER_DBC_PATH);
  std::map<std::string, std::uint32_t> from_table;
  for (const auto& m : kMessageSet) {
    REQUIRE(&message_spec(m.kind) == &m);  // one row a kind
    from_table[std::string(m.name)] = message_id(m.kind, 0, m.per_sender ? Role::hsi : m.sender);
    if (m.per_sender) from_table[std::string(m.top_name)] = message_id(m.kind, 0, Role::top);
    for (std::uint32_t id = m.base; id < m.base + id_count(m); ++id) {
      FrameAddress a;
      REQUIRE(classify(id, a) == DecodeError::none);
      CHECK(a.kind == m.kind);
      CHECK(message_id(a.kind, a.pair, a.role) == id);
      CHECK(message_name(a) == (m.per_sender && a.role == Role::top ? m.top_name : m.name));
    }
  }
  // The DBC describes pair 0: each of its messages is the table's, at the table's id, and no other.
  std::map<std::string, std::uint32_t> from_dbc;
  for (const auto& [name, message] : dbc) from_dbc[name] = message.id;
  CHECK(from_table == from_dbc);
  // No two rows share an id, and every other classic id is no lever message.
  std::size_t ids = 0;
  for (std::uint32_t id = 0; id <= kMaxStandardId; ++id) {
    FrameAddress a;
    ids += classify(id, a) == DecodeError::none ? 1 : 0;
  }
  std::size_t expected = 0;
  for (const auto& m : kMessageSet) expected += id_count(m);
  CHECK(ids == expected);
}

TEST_CASE("every opcode the DBC allows has one name, and no two share it", "[protocol][dbc]") {
  const auto dbc = parse_dbc(LEVER_DBC_PATH);
  const auto& opcode = dbc.at("LeverCommand").signals.at("Opcode");
  std::set<int> codes;
  std::set<std::string_view> names;
  for (const auto op : kAllOpcodes) {
    codes.insert(static_cast<int>(op));
    names.insert(name(op));
    CHECK(name(op) != "unknown");
  }
  CHECK(names.size() == std::size(kAllOpcodes));
  CHECK(codes.size() == std::size(kAllOpcodes));
  CHECK(*codes.begin() == static_cast<int>(opcode.min));
  CHECK(*codes.rbegin() == static_cast<int>(opcode.max));
  CHECK(codes.size() == static_cast<std::size_t>(opcode.max - opcode.min + 1));
}
