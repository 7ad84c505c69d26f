// The displayed force's distortion split by cause: each cause shows up in its own share and nowhere else.
#include <catch2/catch.hpp>

#include "lever/hil/simulation.hpp"

using namespace lever;
using namespace lever::hil;

namespace {

SimResult wall_tap(double p, double filter_hz, const NetworkParams& network) {
  SimConfig c;
  c.scenario = ScenarioKind::wall_tap;
  c.duration_s = 6.0;
  c.network = network;
  c.velocity_codec = {codec::Mode::deadband, p, 0.0, 0.0};
  c.force_codec = {codec::Mode::deadband, p, 0.0, filter_hz};
  return run_simulation(c);
}

}  // namespace

TEST_CASE("a lossless link at p = 0 distorts nothing but by its delay", "[hil][metrics]") {
  const auto lan = wall_tap(0.0, 0.0, {});
  CHECK(lan.nominal_delay_ticks == 1);
  CHECK(lan.force_jnd_violation_link == 0.0);
  CHECK(lan.force_jnd_violation_codec == 0.0);
  CHECK(lan.force_jnd_violation_filter == 0.0);

  const auto far = wall_tap(0.0, 0.0, {20.0, 0.0, 0.0, true});
  CHECK(far.nominal_delay_ticks == 21);
  CHECK(far.force_jnd_violation > 0.05);  // felt: 20 ms late during fast taps
  CHECK(far.force_jnd_violation_link == 0.0);
  CHECK(far.force_jnd_violation_codec == 0.0);
}

TEST_CASE("loss and jitter are the link's, the deadband the codec's, the lag the prefilter's", "[hil][metrics]") {
  const auto lossy = wall_tap(0.0, 0.0, {2.0, 1.0, 0.05, true});
  CHECK(lossy.force_jnd_violation_link > 0.0);
  CHECK(lossy.force_jnd_violation_codec == 0.0);
  CHECK(lossy.force_jnd_violation_filter == 0.0);

  const auto deadband = wall_tap(0.2, 0.0, {});
  CHECK(deadband.force_jnd_violation_codec > 0.0);
  CHECK(deadband.force_jnd_violation_filter == 0.0);
  // Lossless and without jitter, the HSI displays at k what a lossless receiver held at k - delay: the two
  // shares differ only by the run's first and last ticks.
  CHECK(deadband.force_jnd_violation_link == Approx(deadband.force_jnd_violation_codec).margin(0.001));

  const auto filtered = wall_tap(0.0, 30.0, {});
  CHECK(filtered.prefilter_delay_ms == Approx(5.305).margin(0.001));  // 1 / (2 pi 30 Hz)
  CHECK(filtered.force_jnd_violation_filter > 0.0);
  CHECK(filtered.force_jnd_violation_codec == 0.0);
}
