// The CAN message set: ids, round trips, and decoding errors as codes.
#include <algorithm>
#include <catch2/catch.hpp>

#include "lever/codec/config.hpp"
#include "lever/common/rng.hpp"
#include "lever/protocol/fault_names.hpp"
#include "lever/protocol/messages.hpp"
#include "random_messages.hpp"

using namespace lever::protocol;

TEST_CASE("ids carry the pair, and lower ids win arbitration for commands and data", "[protocol]") {
  CHECK(command_id(0) == 0x080);
  CHECK(motion_id(3) == 0x103);
  CHECK(force_id(15) == 0x11F);
  CHECK(heartbeat_id(0, Role::hsi) == 0x700);
  CHECK(heartbeat_id(2, Role::top) == 0x705);
  CHECK(command_id(15) < motion_id(0));
  CHECK(force_id(15) < energy_id(0, Role::hsi));
  CHECK(energy_id(15, Role::top) == 0x13F);
  CHECK(energy_id(15, Role::top) < settings_id(0, Role::hsi));
  CHECK(settings_id(0, Role::hsi) == 0x140);
  CHECK(settings_id(15, Role::top) == 0x15F);
  CHECK(settings_id(15, Role::top) < heartbeat_id(0, Role::hsi));
  CHECK(heartbeat_id(15, Role::top) <= kMaxStandardId);

  FrameAddress a;
  REQUIRE(classify(0x705, a) == DecodeError::none);
  CHECK(a.kind == MessageKind::heartbeat);
  CHECK(a.pair == 2);
  CHECK(a.role == Role::top);
  REQUIRE(classify(0x123, a) == DecodeError::none);
  CHECK(a.kind == MessageKind::energy);
  CHECK(a.pair == 1);
  CHECK(a.role == Role::top);
  REQUIRE(classify(0x145, a) == DecodeError::none);
  CHECK(a.kind == MessageKind::settings);
  CHECK(a.pair == 2);
  CHECK(a.role == Role::top);
  CHECK(classify(0x160, a) == DecodeError::unknown_id);
  CHECK(classify(0x720, a) == DecodeError::unknown_id);
  CHECK(classify(0x7FF, a) == DecodeError::unknown_id);
}

TEST_CASE("every message survives pack and decode for random contents", "[protocol]") {
  lever::Rng rng(1);
  FrameAddress a;
  for (int i = 0; i < 2000; ++i) {
    const auto pair = static_cast<std::uint8_t>(rng.next() % kPairCount);
    MotionMessage m;
    m.position = static_cast<std::int16_t>(rng.next());
    m.velocity = static_cast<std::int16_t>(rng.next());
    m.tick = static_cast<std::uint16_t>(rng.next());
    m.seq = static_cast<std::uint8_t>(rng.next());
    m.flags = {(rng.next() & 1) != 0, (rng.next() & 1) != 0, (rng.next() & 1) != 0,
               (rng.next() & 1) ? lever::codec::Mode::predictive : lever::codec::Mode::deadband, (rng.next() & 1) != 0};
    MotionMessage back;
    REQUIRE(decode(pack(m, pair), back, a) == DecodeError::none);
    CHECK(a.pair == pair);
    CHECK((back.position == m.position && back.velocity == m.velocity && back.tick == m.tick && back.seq == m.seq));
    CHECK((back.flags.value_saturated == m.flags.value_saturated && back.flags.refresh == m.flags.refresh &&
           back.flags.velocity_saturated == m.flags.velocity_saturated && back.flags.mode == m.flags.mode &&
           back.flags.restart == m.flags.restart));

    ForceMessage f;
    f.force = static_cast<std::int32_t>(rng.next() % (1u << 24)) - (1 << 23);
    f.tick = static_cast<std::uint16_t>(rng.next());
    f.seq = static_cast<std::uint8_t>(rng.next());
    f.flags.refresh = (rng.next() & 1) != 0;
    f.flags.restart = (rng.next() & 1) != 0;
    ForceMessage fback;
    REQUIRE(decode(pack(f, pair), fback, a) == DecodeError::none);
    CHECK((fback.force == f.force && fback.tick == f.tick && fback.seq == f.seq &&
           fback.flags.refresh == f.flags.refresh && fback.flags.restart == f.flags.restart));

    const HeartbeatMessage h = lever::test::random_heartbeat(rng);
    const Role role = (rng.next() & 1) ? Role::top : Role::hsi;
    HeartbeatMessage hback;
    REQUIRE(decode(pack(h, pair, role), hback, a) == DecodeError::none);
    CHECK(a.role == role);
    CHECK((hback.arming_parity == h.arming_parity && hback.peer_arming_parity == h.peer_arming_parity &&
           hback.peer_arming_known == h.peer_arming_known));
    CHECK((hback.state == h.state && hback.position_valid == h.position_valid && hback.faults == h.faults &&
           hback.last_data_seq == h.last_data_seq && hback.seq_gaps == h.seq_gaps &&
           hback.rejected_frames == h.rejected_frames && hback.counter == h.counter &&
           hback.encoder_errors == h.encoder_errors));

    const SettingsMessage st = lever::test::random_settings(rng);
    SettingsMessage stback;
    REQUIRE(decode(pack(st, pair, role), stback, a) == DecodeError::none);
    CHECK(a.role == role);
    CHECK(a.kind == MessageKind::settings);
    CHECK(stback == st);

    CommandMessage c;
    c.opcode = static_cast<Opcode>(1 + rng.next() % 6);
    c.to_hsi = (rng.next() & 1) != 0;
    c.to_top = (rng.next() & 1) != 0;
    c.direction = (rng.next() & 1) ? Direction::force : Direction::motion;
    c.mode = (rng.next() & 1) ? lever::codec::Mode::predictive : lever::codec::Mode::deadband;
    c.p = static_cast<std::uint16_t>(rng.next());
    c.floor = static_cast<std::uint16_t>(rng.next());
    c.filter_hz = static_cast<std::uint16_t>(rng.next());
    CommandMessage cback;
    REQUIRE(decode(pack(c, pair), cback, a) == DecodeError::none);
    CHECK((cback.opcode == c.opcode && cback.to_hsi == c.to_hsi && cback.to_top == c.to_top &&
           cback.direction == c.direction && cback.mode == c.mode && cback.p == c.p && cback.floor == c.floor &&
           cback.filter_hz == c.filter_hz));
  }
}

TEST_CASE("a force beyond the 24-bit field saturates and says so, never wraps", "[protocol]") {
  FrameAddress a;
  ForceMessage f;
  f.force = 50'000'000;  // 500 N
  ForceMessage back;
  REQUIRE(decode(pack(f, 0), back, a) == DecodeError::none);
  CHECK(back.force == kForceCodeMax);
  CHECK(back.flags.value_saturated);
  f.force = -50'000'000;
  REQUIRE(decode(pack(f, 0), back, a) == DecodeError::none);
  CHECK(back.force == kForceCodeMin);
  CHECK(back.flags.value_saturated);
  CHECK(kForceCodeMax * kForceLsb > 50.0);  // the +-50 N the levers need fit
  CHECK(kForceLsb <= 1e-3);                 // at 1 mN or better
}

TEST_CASE("malformed frames are error codes", "[protocol]") {
  FrameAddress a;
  MotionMessage m;
  CanFrame good = pack(MotionMessage{}, 0);

  CanFrame short_frame = good;
  short_frame.dlc = 7;
  CHECK(decode(short_frame, m, a) == DecodeError::wrong_dlc);
  CanFrame long_frame = good;
  long_frame.dlc = 15;  // CAN FD length codes do not belong here
  CHECK(decode(long_frame, m, a) == DecodeError::wrong_dlc);

  CanFrame wrong_kind = pack(ForceMessage{}, 0);
  CHECK(decode(wrong_kind, m, a) == DecodeError::unknown_id);
  CanFrame foreign = good;
  foreign.id = 0x123;
  CHECK(decode(foreign, m, a) == DecodeError::unknown_id);

  CanFrame reserved_flag = good;
  reserved_flag.data[7] = 0x20;
  CHECK(decode(reserved_flag, m, a) == DecodeError::out_of_range);

  HeartbeatMessage h;
  CanFrame bad_state = pack(HeartbeatMessage{}, 0, Role::hsi);
  bad_state.data[0] = 9;
  CHECK(decode(bad_state, h, a) == DecodeError::out_of_range);
  CanFrame unused_state_code = pack(HeartbeatMessage{}, 0, Role::hsi);
  unused_state_code.data[0] = 0xE5;  // state 5 (none such), with every handshake bit set
  CHECK(decode(unused_state_code, h, a) == DecodeError::out_of_range);

  CommandMessage c;
  CanFrame bad_opcode = pack(CommandMessage{}, 0);
  bad_opcode.data[0] = 0;
  CHECK(decode(bad_opcode, c, a) == DecodeError::out_of_range);
  bad_opcode.data[0] = 7;
  CHECK(decode(bad_opcode, c, a) == DecodeError::out_of_range);
  CanFrame bad_mode = pack(CommandMessage{}, 0);
  bad_mode.data[1] = static_cast<std::uint8_t>(bad_mode.data[1] | (3u << 3));
  CHECK(decode(bad_mode, c, a) == DecodeError::out_of_range);

  SettingsMessage st;
  CanFrame settings_good = pack(SettingsMessage{}, 3, Role::top);
  REQUIRE(decode(settings_good, st, a) == DecodeError::none);
  for (const int mode : {2, 3}) {
    CanFrame bad_settings_mode = settings_good;
    bad_settings_mode.data[0] = static_cast<std::uint8_t>(mode);
    CHECK(decode(bad_settings_mode, st, a) == DecodeError::out_of_range);
  }
  CanFrame settings_reserved = settings_good;
  settings_reserved.data[1] = 0x80;  // bit 15
  CHECK(decode(settings_reserved, st, a) == DecodeError::out_of_range);
  CanFrame settings_short = settings_good;
  settings_short.dlc = 6;
  CHECK(decode(settings_short, st, a) == DecodeError::wrong_dlc);
  CHECK(decode(pack(HeartbeatMessage{}, 3, Role::top), st, a) == DecodeError::unknown_id);
  CHECK(decode(settings_good, h, a) == DecodeError::unknown_id);

  ForceMessage f;
  CanFrame reserved_byte = pack(ForceMessage{}, 0);
  reserved_byte.data[7] = 1;
  CHECK(decode(reserved_byte, f, a) == DecodeError::out_of_range);
}

TEST_CASE("every possible payload decodes to a value or an error, never anything else", "[protocol]") {
  // Valid ids of every kind and every pair with random payloads and random lengths, so that most frames get
  // past the id and length checks into payload decoding (random ids alone reached it 0.25 % of the time).
  // Decoding must return a defined code, and a frame that decodes must re-pack to the very same bytes:
  // nothing in a payload may be silently dropped or invented.
  lever::Rng rng(99);
  const std::uint32_t bases[] = {kCommandBase, kMotionBase, kForceBase};
  constexpr std::size_t kKinds = 6;
  int decoded[kKinds] = {}, rejected[kKinds] = {};
  for (int i = 0; i < 60000; ++i) {
    const std::size_t kind = rng.next() % kKinds;
    const auto pair = static_cast<std::uint8_t>(rng.next() % kPairCount);
    const Role role = (rng.next() & 1) ? Role::top : Role::hsi;
    CanFrame f;
    f.id = kind == 3   ? heartbeat_id(pair, role)
           : kind == 4 ? energy_id(pair, role)
           : kind == 5 ? settings_id(pair, role)
                       : bases[kind] + pair;
    f.dlc = static_cast<std::uint8_t>(rng.next() % 8 == 0 ? rng.next() % 16 : 8);  // mostly the right length
    for (auto& b : f.data) b = static_cast<std::uint8_t>(rng.next());
    // Sparse payloads too: random bytes almost always set some reserved bit.
    if (rng.next() % 2 == 0)
      for (auto& b : f.data) b = static_cast<std::uint8_t>(b & rng.next() & rng.next());
    FrameAddress a;
    DecodeError e = DecodeError::none;
    CanFrame again{};
    switch (kind) {
      case 0: {
        CommandMessage c;
        e = decode(f, c, a);
        if (e == DecodeError::none) again = pack(c, pair);
        break;
      }
      case 1: {
        MotionMessage m;
        e = decode(f, m, a);
        if (e == DecodeError::none) again = pack(m, pair);
        break;
      }
      case 2: {
        ForceMessage m;
        e = decode(f, m, a);
        if (e == DecodeError::none) again = pack(m, pair);
        break;
      }
      case 4: {
        EnergyMessage m;
        e = decode(f, m, a);
        if (e == DecodeError::none) again = pack(m, pair, role);
        break;
      }
      case 5: {
        SettingsMessage m;
        e = decode(f, m, a);
        if (e == DecodeError::none) again = pack(m, pair, role);
        break;
      }
      default: {
        HeartbeatMessage h;
        e = decode(f, h, a);
        if (e == DecodeError::none) again = pack(h, pair, role);
        break;
      }
    }
    REQUIRE(static_cast<int>(e) <= static_cast<int>(DecodeError::out_of_range));
    if (e == DecodeError::none) {
      ++decoded[kind];
      CHECK(a.pair == pair);
      INFO("kind " << kind << " id " << f.id);
      CHECK(again.id == f.id);
      CHECK(again.dlc == f.dlc);
      // Command frames leave bits 13-15 as reserved zero, settings frames bit 15; no other padding.
      CHECK(std::equal(f.data.begin(), f.data.end(), again.data.begin()));
    } else {
      ++rejected[kind];
    }
  }
  // Every kind was exercised on both paths, decoded and refused, hundreds of times each.
  for (std::size_t k = 0; k < kKinds; ++k) {
    INFO("kind " << k);
    CHECK(decoded[k] > 200);
    CHECK(rejected[k] > 200);
  }
}

TEST_CASE("a parameter becomes the nearest code of its field, clipped", "[protocol]") {
  CHECK(unsigned_code(0.1, kPLsb) == 1000);
  CHECK(unsigned_code(0.12345, kPLsb) == 1235);  // a configuration's extra digits round to the field's
  CHECK(unsigned_code(0.02, kFloorLsb) == 20);
  CHECK(unsigned_code(30.0, kFilterHzLsb) == 300);
  CHECK(unsigned_code(0.0, kPLsb) == 0);
  CHECK(unsigned_code(0.00004, kPLsb) == 0);
  CHECK(unsigned_code(0.00005, kPLsb) == 1);
  CHECK(unsigned_code(100.0, kFloorLsb) == 65535);  // past the field: its largest code
  CHECK(unsigned_code(-1.0, kFloorLsb) == 0);
  // Every code of the command comes back as itself through the lever's double.
  for (std::uint32_t code = 0; code <= 65535; ++code) {
    REQUIRE(unsigned_code(code * kPLsb, kPLsb) == code);
    REQUIRE(unsigned_code(code * kFloorLsb, kFloorLsb) == code);
    REQUIRE(unsigned_code(code * kFilterHzLsb, kFilterHzLsb) == code);
  }
}

TEST_CASE("the codec's settings: the command and the settings frame carry them alike, each way by one conversion",
          "[protocol]") {
  const lever::codec::Config<double> wanted{lever::codec::Mode::predictive, 0.12345, 0.05, 30.0};
  CommandMessage command;
  set_codec_settings(command, wanted);
  CHECK(command.mode == lever::codec::Mode::predictive);
  CHECK(command.p == 1235);  // the nearest step, as unsigned_code
  CHECK(command.floor == 50);
  CHECK(command.filter_hz == 300);
  SettingsMessage settings;
  settings.changes = 7;  // not a codec setting: neither set nor compared
  set_codec_settings(settings, codec_settings(command));
  CHECK(settings.changes == 7);
  CHECK(same_codec_settings(settings, command));
  const auto read = codec_settings(settings);
  CHECK(read.mode == lever::codec::Mode::predictive);
  CHECK(read.p == Approx(0.1235));
  CHECK(read.floor == Approx(0.05));
  CHECK(read.filter_hz == Approx(30.0));
  // Each field is compared: one step apart in any of them is another setting.
  for (int field = 0; field < 4; ++field) {
    SettingsMessage other = settings;
    if (field == 0) other.mode = lever::codec::Mode::deadband;
    if (field == 1) ++other.p;
    if (field == 2) ++other.floor;
    if (field == 3) ++other.filter_hz;
    CHECK_FALSE(same_codec_settings(other, command));
  }
  // Past its field, a value is its field's largest step (a configuration may hold more range than a frame).
  set_codec_settings(command, {lever::codec::Mode::deadband, 10.0, 100.0, 10000.0});
  CHECK(command.p == 65535);
  CHECK(command.floor == 65535);
  CHECK(command.filter_hz == 65535);
}

TEST_CASE("fault names: every known bit by its name in table order, unknown bits in hex, one separator", "[protocol]") {
  CHECK(fault_names(0, ", ", "none") == "none");
  CHECK(fault_names(0, "+").empty());
  CHECK(fault_names(bit(Fault::can_bus) | bit(Fault::comms_timeout), ", ") == "comms_timeout, can_bus");
  CHECK(fault_names(bit(Fault::encoder) | bit(Fault::timing), "|") == "encoder|timing");
  CHECK(fault_names(0x8001, ", ") == "comms_timeout, unknown bits 0x8000");
  CHECK(fault_name_list(0x0C00) == std::vector<std::string>{"can_bus", "unknown bits 0x0800"});
  FaultBits every = 0;
  for (const Fault f : kAllFaults) every = static_cast<FaultBits>(every | bit(f));
  CHECK(fault_name_list(every).size() == std::size(kAllFaults));
  CHECK(unknown_fault_bits(every) == 0);
}

TEST_CASE("codec modes: one spelling each, distinct, for every mode the wire can carry", "[protocol]") {
  CHECK(lever::codec::name(lever::codec::Mode::deadband) == "deadband");
  CHECK(lever::codec::name(lever::codec::Mode::predictive) == "predictive");
  for (const auto a : lever::codec::kAllModes) {
    CHECK(lever::codec::name(a) != "unknown");
    for (const auto b : lever::codec::kAllModes)
      if (a != b) CHECK(lever::codec::name(a) != lever::codec::name(b));
  }
}
