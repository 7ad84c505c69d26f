// Change detection, not fidelity: the documented wall-tap and sphere-3dof tables (docs/hil-model.md) must stay
// where they were. The mean of seeds 1-3 of each row stays within the per-seed spread measured over ten seeds
// (tests/hil/change_detection_*.json, written by scripts/hil-change-bounds-*), so a change that moves a figure
// beyond the model's own seed-to-seed variation fails here, whether it moves toward the paper or away from it.
// When that is meant, rerun the script, update the docs' table, and say in the commit which figures moved and why.
// How near the paper the figures are: test_paper_fidelity.cpp.
#include <catch2/catch.hpp>
#include <fstream>
#include <nlohmann/json.hpp>

#include "lever/hil/simulation.hpp"
#include "lever/hil/sphere3dof.hpp"

using namespace lever;
using namespace lever::hil;

TEST_CASE("change detection: the wall-tap table stays within its spread over seeds", "[hil][change-detection]") {
  std::ifstream in(LEVER_CHANGE_DETECTION_WALL_TAP);
  REQUIRE(in.good());
  const auto bounds = nlohmann::json::parse(in);
  REQUIRE(bounds.at("rows").size() == 6u);
  for (const auto& row : bounds.at("rows")) {
    const std::string name = row.at("name").get<std::string>() + " " + row.at("options").get<std::string>();
    SECTION(name) {
      SimConfig c;
      c.scenario = ScenarioKind::wall_tap;
      c.duration_s = 20.0;
      const auto mode = row.at("mode") == "predictive" ? codec::Mode::predictive : codec::Mode::deadband;
      const double p = row.at("p");
      c.velocity_codec = {mode, p, row.at("floor_velocity").get<double>(), row.at("filter_hz_velocity").get<double>()};
      c.force_codec = {mode, p, row.at("floor_force").get<double>(), row.at("filter_hz_force").get<double>()};
      double velocity = 0, force = 0, jnd = 0;
      constexpr int kSeeds = 3;
      for (int seed = 1; seed <= kSeeds; ++seed) {
        c.seed = static_cast<std::uint64_t>(seed);
        const auto r = run_simulation(c);
        velocity += r.velocity_packet_rate / kSeeds;
        force += r.force_packet_rate / kSeeds;
        jnd += r.force_jnd_violation / kSeeds;
      }
      auto within = [](const nlohmann::json& b, double v) {
        return b.at("min").get<double>() <= v && v <= b.at("max").get<double>();
      };
      INFO(name << ": velocity " << velocity << " force " << force << " jnd " << jnd);
      CHECK(within(row.at("velocity"), velocity));
      CHECK(within(row.at("force"), force));
      CHECK(within(row.at("jnd"), jnd));
    }
  }
}

TEST_CASE("change detection: the sphere-3dof table stays within its spread over seeds",
          "[hil][sphere][change-detection]") {
  std::ifstream in(LEVER_CHANGE_DETECTION_SPHERE_3DOF);
  REQUIRE(in.good());
  const auto bounds = nlohmann::json::parse(in);
  REQUIRE(bounds.at("rows").size() == 8u);
  auto codec_of = [](const nlohmann::json& j) {
    return codec::Config<double>{j.at("mode") == "predictive" ? codec::Mode::predictive : codec::Mode::deadband,
                                 j.at("p").get<double>(), j.at("floor").get<double>(), j.at("filter_hz").get<double>()};
  };
  for (const auto& row : bounds.at("rows")) {
    const std::string name = row.at("name").get<std::string>() + " " + row.at("options").get<std::string>();
    SECTION(name) {
      SphereConfig c;
      c.duration_s = bounds.at("duration_s").get<double>();
      c.velocity_codec = codec_of(row.at("velocity_codec"));
      c.force_codec = codec_of(row.at("force_codec"));
      double velocity = 0, force = 0, jnd = 0, contact = 0;
      constexpr int kSeeds = 3;
      for (int seed = 1; seed <= kSeeds; ++seed) {
        c.seed = static_cast<std::uint64_t>(seed);
        const auto r = run_sphere(c);
        velocity += r.velocity_packet_rate / kSeeds;
        force += r.force_packet_rate / kSeeds;
        jnd += r.force_jnd_violation / kSeeds;
        contact += r.contact_share / kSeeds;
      }
      auto within = [](const nlohmann::json& b, double v) {
        return b.at("min").get<double>() <= v && v <= b.at("max").get<double>();
      };
      INFO(name << ": velocity " << velocity << " force " << force << " jnd " << jnd << " contact " << contact);
      CHECK(within(row.at("velocity"), velocity));
      CHECK(within(row.at("force"), force));
      CHECK(within(row.at("jnd"), jnd));
      CHECK(within(row.at("contact"), contact));
    }
  }
}
