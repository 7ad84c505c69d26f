// lever-view's screen text, its JSON and the status lines it reads, without a terminal.
#include <catch2/catch.hpp>
#include <string>

#include "lever/protocol/messages.hpp"
#include "pair_monitor.hpp"
#include "refresh_meter.hpp"
#include "screen_text.hpp"
#include "snapshot_json.hpp"
#include "status_line.hpp"

using namespace lever;
using protocol::Role;

namespace {

constexpr std::int64_t kT0 = 1'700'000'000'000'000;

std::string screen_of(const view::Snapshot& s, bool utf8 = true) {
  std::string text;
  for (const auto& line : view::render(s, {"vcan0", true, 0}, {120, utf8, false, 1e6, std::nullopt}))
    text += line.text + "\n";
  return text;
}

view::PairMonitor armed_pair_with_faulted_top() {
  view::PairMonitor m;
  protocol::HeartbeatMessage h;
  h.state = protocol::LeverState::armed;
  h.position_valid = true;
  m.on_frame(protocol::pack(h, 0, Role::hsi), kT0);
  h.state = protocol::LeverState::fault;
  h.faults = protocol::bit(protocol::Fault::force_stale) | protocol::bit(protocol::Fault::can_bus);
  m.on_frame(protocol::pack(h, 0, Role::top), kT0);
  protocol::MotionMessage motion;
  motion.position = 1000;  // 0.3835 rad
  m.on_frame(protocol::pack(motion, 0), kT0);
  return m;
}

}  // namespace

TEST_CASE("lever-fw's and lever-bridge's status lines are read, anything else is not", "[view]") {
  const auto lever = view::parse_status_line(
      R"({"role":"top","pair":2,"state":"armed","faults":["timing"],"position_rad":0.25,"position_valid":true,)"
      R"("velocity_rad_s":-1.5,"force_n":null,"torque_nm":0.75,"data_sent":1234})");
  const auto* l = std::get_if<view::LeverStatus>(&lever);
  REQUIRE(l != nullptr);
  CHECK(l->pair == 2);
  CHECK(l->role == Role::top);
  CHECK(l->state == "armed");
  CHECK(l->faults == std::vector<std::string>{"timing"});
  CHECK(*l->position_rad == 0.25);
  CHECK(l->force_n == std::nullopt);
  CHECK(*l->torque_nm == 0.75);
  CHECK(*l->data_sent == 1234);

  const auto bridge = view::parse_status_line(
      R"({"to_network":{"frames_per_s":512.0},"from_network":{"frames_per_s":498.0,"sequence_gaps":3,)"
      R"("reordered":1},"latency_us":{"p99":812.5},"bus_load":0.221,"can":"up"})");
  const auto* b = std::get_if<view::BridgeStatus>(&bridge);
  REQUIRE(b != nullptr);
  CHECK(*b->bus_load == 0.221);
  CHECK(*b->to_network_per_s == 512.0);
  CHECK(b->sequence_gaps == 3);
  CHECK(*b->latency_p99_us == 812.5);

  for (const char* other : {"", "not json", "[1,2]", R"({"role":"middle","pair":0})", R"({"role":"hsi","pair":16})",
                            R"({"role":"hsi"})", R"({"samples":10})"})
    CHECK(std::holds_alternative<std::monostate>(view::parse_status_line(other)));
}

TEST_CASE("the screen names each lever's state, homing and faults, and the data it carries", "[view]") {
  auto m = armed_pair_with_faulted_top();
  const std::string text = screen_of(m.snapshot(kT0 + 10'000));
  CHECK(text.find("pair 0") != std::string::npos);
  CHECK(text.find("HSI  armed       yes") != std::string::npos);
  CHECK(text.find("TOP  fault       yes") != std::string::npos);
  CHECK(text.find("force_stale,can_bus") != std::string::npos);
  CHECK(text.find("+0.3835") != std::string::npos);
  CHECK(text.find("kernel drops 0") != std::string::npos);
  CHECK(text.find("of 1 Mbit/s") != std::string::npos);
  // 40 ms later still armed; after 100 ms without a heartbeat, silent.
  CHECK(screen_of(m.snapshot(kT0 + 150'000)).find("silent 0.1s") != std::string::npos);
}

TEST_CASE("what only a status line says is marked as such", "[view]") {
  auto m = armed_pair_with_faulted_top();
  view::LeverStatus top;
  top.role = Role::top;
  top.position_rad = 0.125;
  top.torque_nm = -0.5;
  m.on_status(top, 0, kT0);
  const std::string text = screen_of(m.snapshot(kT0 + 1000));
  CHECK(text.find("+0.1250*") != std::string::npos);
  CHECK(text.find("-0.500*") != std::string::npos);
  CHECK(text.find("* from the lever's status line") != std::string::npos);
  CHECK(text.find("TOP position*") != std::string::npos);
}

TEST_CASE("a sparkline spans its samples' range, blank where there was no value", "[view]") {
  const std::vector<std::optional<float>> ramp{0.0f, 1.0f, std::nullopt, 7.0f};
  CHECK(view::sparkline(ramp, 4, false) == "_. #");
  CHECK(view::sparkline(ramp, 6, false) == "  _. #");  // the newest sample stays in the last column
  CHECK(view::sparkline(ramp, 2, false) == " -");      // only the newest that fit, scaled among themselves
  CHECK(view::sparkline(ramp, 4, true) == "\u2581\u2582 \u2588");
  CHECK(view::sparkline({2.0f, 2.0f}, 2, false) == "--");  // flat: the middle
}

TEST_CASE("lines are cut by characters, not bytes", "[view]") {
  CHECK(view::clip_columns("abc", 2) == "ab");
  CHECK(view::clip_columns("\u2581\u2582\u2583", 2) == "\u2581\u2582");
  CHECK(view::clip_columns("ab", 5) == "ab");
}

TEST_CASE("the JSON gives the screen's figures by name", "[view]") {
  auto m = armed_pair_with_faulted_top();
  const auto j = view::to_json(m.snapshot(kT0 + 10'000), {"vcan0", true, 7});
  CHECK(j["interface"] == "vcan0");
  CHECK(j["kernel_drops"] == 7);
  const auto& p = j["pairs"][0];
  CHECK(p["hsi"]["state"] == "armed");
  CHECK(p["hsi"]["homed"] == true);
  CHECK(p["top"]["faults"] == nlohmann::json::array({"force_stale", "can_bus"}));
  CHECK(p["hsi_position_rad"].get<double>() == Approx(1000 * protocol::kPositionLsbRad));
  CHECK(p["top_force_n"].is_null());
  CHECK(p["motion"]["frames"] == 1);
  CHECK(j["bus"]["frames"] == 3);
}

TEST_CASE("the screen's own refresh rate over its last ten intervals", "[view]") {
  view::RefreshMeter meter;
  CHECK(meter.per_second() == std::nullopt);
  meter.on_draw(0);
  CHECK(meter.per_second() == std::nullopt);
  for (int i = 1; i <= 30; ++i) meter.on_draw(i * 100'000);
  CHECK(*meter.per_second() == Approx(10.0));
  for (int i = 1; i <= 5; ++i) meter.on_draw(3'000'000 + i * 200'000);  // then a slower screen
  CHECK(*meter.per_second() == Approx(10.0 / 1.5));
  auto m = armed_pair_with_faulted_top();
  view::ScreenOptions options;
  options.pictures_per_s = 9.96;
  CHECK(view::render(m.snapshot(kT0), {"vcan0", true, 0}, options)[0].text.find("screen 10.0/s") != std::string::npos);
  // A frozen picture says so where a narrow terminal does not cut it off.
  options.frozen = true;
  CHECK(view::render(m.snapshot(kT0), {"vcan0", true, 0}, options)[0].text.rfind("lever-view  vcan0  [FROZEN]", 0) ==
        0);
}

TEST_CASE("the screen shows the settings each direction's sender reports, or that none was heard", "[view]") {
  auto m = armed_pair_with_faulted_top();
  std::string text = screen_of(m.snapshot(kT0 + 10'000));
  CHECK(text.find("settings not heard") != std::string::npos);
  protocol::SettingsMessage st;
  st.mode = codec::Mode::predictive;
  st.p = 250;
  st.floor = 50;
  st.filter_hz = 300;
  st.taring = true;
  m.on_frame(protocol::pack(st, 0, Role::top), kT0 + 1);
  st.mode = codec::Mode::deadband;
  st.p = 1000;
  st.floor = 20;
  st.filter_hz = 0;
  st.taring = false;
  m.on_frame(protocol::pack(st, 0, Role::hsi), kT0 + 2);
  text = screen_of(m.snapshot(kT0 + 10'000));
  CHECK(text.find("predictive p 2.50 % floor 0.050 N filter 30.0 Hz  taring") != std::string::npos);
  CHECK(text.find("deadband p 10.00 % floor 0.020 rad/s filter off") != std::string::npos);
  // Each below its own direction's row.
  CHECK(text.find("motion HSI>TOP") < text.find("deadband p 10.00 %"));
  CHECK(text.find("deadband p 10.00 %") < text.find("force  TOP>HSI"));
  CHECK(text.find("force  TOP>HSI") < text.find("predictive p 2.50 %"));
  const auto j = view::to_json(m.snapshot(kT0 + 10'000), {"vcan0", true, 0});
  const auto& top = j["pairs"][0]["top"];
  CHECK(top["settings"]["mode"] == "predictive");
  CHECK(top["settings"]["p"].get<double>() == Approx(0.025));
  CHECK(top["settings"]["filter_hz"].get<double>() == Approx(30.0));
  CHECK(top["settings"]["taring"] == true);
  CHECK(top["settings_frames"] == 1);
}
