// Change detection, not fidelity: the documented wall-tap and sphere-3dof tables (docs/hil-model.md) must stay
// exactly where they were. The HIL gives the same bytes on every architecture (the cross test), so each row's
// figures for seeds 1-3 are pinned exactly as `lever-hil run --json` reported them when
// hil/experiments/hil-change-bounds-* last ran (tests/hil/change_detection_*.json). Any change to the model, the
// firmware core or the codec that moves a single packet, tick of contact or JND-tick of one of those runs fails here,
// whether it moves toward the paper or away from it. When that is meant, rerun the scripts, update the docs' tables,
// and say in the commit which figures moved and why. The wall-tap rows run the paper's setup (one controller, the
// HSI's force loop) and are counted as the paper counts (the deadband's packets), with every data frame beside them.
// How near the paper the figures are: test_paper_fidelity.cpp.
#include <catch2/catch.hpp>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lever/hil/simulation.hpp"
#include "lever/hil/sphere3dof.hpp"

using namespace lever;
using namespace lever::hil;

namespace {

struct Figure {
  const char* name;
  double value;
};

nlohmann::json read_pins(const char* path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  return nlohmann::json::parse(in);
}

std::string exact(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// Every figure of one seed's run against its pin, bit for bit.
void check_pinned(const nlohmann::json& pin, const std::vector<Figure>& figures) {
  for (const auto& f : figures) {
    const double pinned = pin.at(f.name).get<double>();
    INFO("seed " << pin.at("seed").get<int>() << " " << f.name << ": pinned " << exact(pinned) << ", now "
                 << exact(f.value));
    CHECK(f.value == pinned);
  }
}

}  // namespace

TEST_CASE("change detection: the wall-tap table's runs give exactly the pinned figures", "[hil][change-detection]") {
  const auto pins = read_pins(LEVER_CHANGE_DETECTION_WALL_TAP);
  REQUIRE(pins.at("rows").size() == 8u);
  for (const auto& row : pins.at("rows")) {
    const std::string name = row.at("name").get<std::string>() + " " + row.at("options").get<std::string>();
    SECTION(name) {
      SimConfig c;
      c.scenario = ScenarioKind::wall_tap;
      c.duration_s = pins.at("duration_s").get<double>();
      const auto mode = row.at("mode") == "predictive" ? codec::Mode::predictive : codec::Mode::deadband;
      const double p = row.at("p");
      c.velocity_codec = {mode, p, row.at("floor_velocity").get<double>(), row.at("filter_hz_velocity").get<double>()};
      c.force_codec = {mode, p, row.at("floor_force").get<double>(), row.at("filter_hz_force").get<double>()};
      REQUIRE(row.at("topology") == "one-controller");
      c.topology = Topology::one_controller;
      set_hsi_force_loop(c, row.at("hsi_force_loop").get<bool>());
      REQUIRE((row.at("motion_velocity") == "adaptive-window" || row.at("motion_velocity") == "difference"));
      c.hsi_firmware.motion_velocity = row.at("motion_velocity") == "adaptive-window"
                                           ? fw::MotionVelocity::adaptive_window
                                           : fw::MotionVelocity::difference;
      c.hsi_firmware.counts_per_rev = c.top_firmware.counts_per_rev = row.at("encoder_counts").get<double>();
      c.encoder_interface =
          row.at("encoder_interface") == "counter" ? EncoderInterface::counter : EncoderInterface::gpio_events;
      REQUIRE((row.at("gauge_chain") == "paper-adc" || row.at("gauge_chain") == "dad141"));
      c.gauge_chain = row.at("gauge_chain") == "paper-adc" ? GaugeChain::paper_adc : GaugeChain::dad141;
      REQUIRE(row.at("pinned").size() == 3u);
      for (const auto& pin : row.at("pinned")) {
        c.seed = pin.at("seed").get<std::uint64_t>();
        const auto r = run_simulation(c);
        check_pinned(pin, {{"velocity", r.velocity_deadband_rate},
                           {"force", r.force_deadband_rate},
                           {"velocity_all", r.velocity_packet_rate},
                           {"force_all", r.force_packet_rate},
                           {"jnd", r.force_jnd_violation},
                           {"velocity_contact", r.velocity_deadband_contact_rate},
                           {"force_contact", r.force_deadband_contact_rate}});
      }
    }
  }
}

TEST_CASE("change detection: the sphere-3dof table's runs give exactly the pinned figures",
          "[hil][sphere][change-detection]") {
  const auto pins = read_pins(LEVER_CHANGE_DETECTION_SPHERE_3DOF);
  REQUIRE(pins.at("rows").size() == 8u);
  auto codec_of = [](const nlohmann::json& j) {
    return codec::Config<double>{j.at("mode") == "predictive" ? codec::Mode::predictive : codec::Mode::deadband,
                                 j.at("p").get<double>(), j.at("floor").get<double>(), j.at("filter_hz").get<double>()};
  };
  for (const auto& row : pins.at("rows")) {
    const std::string name = row.at("name").get<std::string>() + " " + row.at("options").get<std::string>();
    SECTION(name) {
      SphereConfig c;
      c.duration_s = pins.at("duration_s").get<double>();
      c.velocity_codec = codec_of(row.at("velocity_codec"));
      c.force_codec = codec_of(row.at("force_codec"));
      REQUIRE(row.at("pinned").size() == 3u);
      for (const auto& pin : row.at("pinned")) {
        c.seed = pin.at("seed").get<std::uint64_t>();
        const auto r = run_sphere(c);
        check_pinned(pin, {{"velocity", r.velocity_packet_rate},
                           {"force", r.force_packet_rate},
                           {"jnd", r.force_jnd_violation},
                           {"contact", r.contact_share},
                           {"velocity_contact", r.velocity_contact_rate},
                           {"force_contact", r.force_contact_rate}});
      }
    }
  }
}
