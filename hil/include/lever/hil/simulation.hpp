#pragma once
// The testbed in simulated time: two levers (the real firmware core, HsiLever<SimHal> and TopLever<SimHal>),
// their plants, the operator, the wall, one CAN bus per site joined by two bridges over a simulated IP link,
// and injected faults. Before the scenario both levers power up at a random angle, home against their end
// stop and are armed by the host; the scenario's clock starts when both are armed. Deterministic: the same
// configuration and seed give the same results, bit for bit.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "lever/codec/config.hpp"
#include "lever/fw/lever.hpp"
#include "lever/fw/lever_config.hpp"
#include "lever/hil/fault_spec.hpp"
#include "lever/hil/human_operator.hpp"
#include "lever/hil/lever_plant.hpp"
#include "lever/hil/network.hpp"
#include "lever/hil/sim_hal.hpp"
#include "lever/hil/strain_gauge_model.hpp"
#include "lever/hil/wall.hpp"

namespace lever::hil {

using SimHsi = fw::HsiLever<SimHal>;
using SimTop = fw::TopLever<SimHal>;

// Both levers after a tick, for tests that check invariants every tick.
struct SimView {
  double t = 0.0;     // scenario time; negative before the scenario (power-up, homing)
  fw::Tick tick = 0;  // the simulation's tick (each lever counts its own from its power-up)
  const SimHsi& hsi;
  const SimTop& top;
  std::uint64_t hsi_rearms_sent = 0;  // re-arm commands the host addressed to each lever so far
  std::uint64_t top_rearms_sent = 0;
};

struct TraceRow;

// How a lever's controller reads its encoder: as libgpiod edge events (the project's board: two 16-event queues,
// drained every tick, 12 rad/s at 16384 counts per turn), or with a hardware counter (an MCU timer in encoder mode,
// /dev/counterN), which has no queue; the HIL gives the latter an edge queue of QuadratureEncoder::kMaxQueue.
enum class EncoderInterface { gpio_events, counter };
inline constexpr EncoderInterface kAllEncoderInterfaces[] = {EncoderInterface::gpio_events, EncoderInterface::counter};
constexpr std::string_view name(EncoderInterface e) {
  return e == EncoderInterface::counter ? "counter" : "gpio-events";
}

// Where the levers are: both in one controller (the paper's single PC: no bus, each tick's samples reach the other
// lever in that tick), both on one CAN bus, or each on its own site's bus, the buses joined by two lever-bridges
// over an IP link (the network parameters apply only there).
enum class Topology { one_controller, one_site, two_sites };
inline constexpr Topology kAllTopologies[] = {Topology::one_controller, Topology::one_site, Topology::two_sites};
constexpr std::string_view name(Topology t) {
  return t == Topology::one_controller ? "one-controller" : t == Topology::one_site ? "one-site" : "two-sites";
}

// Which chain reads the levers' strain gauges (docs/hil-model.md): the deployment's Modbus weighing amplifier (the
// DAD 141.1, `gauge` below), the paper's instrumentation amplifier and 1 kHz ADC (paper_adc_gauge()), or the one
// that goes with the topology: the paper's in one controller (the paper's setup), the DAD on one or two sites.
enum class GaugeChain : std::uint8_t { topology, dad141, paper_adc };
inline constexpr GaugeChain kAllGaugeChains[] = {GaugeChain::topology, GaugeChain::dad141, GaugeChain::paper_adc};
constexpr std::string_view name(GaugeChain g) {
  return g == GaugeChain::topology ? "topology" : g == GaugeChain::dad141 ? "dad141" : "paper-adc";
}

struct SimConfig;
// The strain-gauge chain the run's levers read: the paper's ADC or the DAD 141.1 (config.gauge), by gauge_chain.
bool reads_paper_gauge(const SimConfig& config);
StrainGaugeParams effective_gauge(const SimConfig& config);
// The contact's settings, a pair designed together (docs/hil-model.md, "The design applied where its low-pass may
// run"): the TOP's reference low-pass and the HSI's contact damping on the run's gauge chain. Without tdpa on the
// TOP, the design's ("The contact designed on seeds of its own", its dampings within the timing budget); under
// tdpa, where the firmware refuses the low-pass, the settings the passivity suite was derived with.
struct ContactSettings {
  double top_reference_cutoff_hz = 0.0;
  double hsi_contact_damping_nms = 0.0;
};
ContactSettings contact_settings(const SimConfig& config);

struct SimConfig {
  ScenarioKind scenario = ScenarioKind::wall_tap;
  double duration_s = 20.0;  // the paper's interval length
  std::uint64_t seed = 1;
  codec::Config<double> velocity_codec{codec::Mode::deadband, 0.1, 0.0, 0.0};  // HSI -> TOP
  codec::Config<double> force_codec{codec::Mode::deadband, 0.1, 0.0, 0.0};     // TOP -> HSI
  Topology topology = Topology::two_sites;
  NetworkParams network{};
  std::vector<FaultSpec> faults;
  double rearm_after_s = 0.3;  // the host re-arms (and if need be re-homes) levers this long after a fault's span ends

  LeverPlantParams hsi_plant{};
  LeverPlantParams top_plant{};
  WallParams wall{};
  GaugeChain gauge_chain = GaugeChain::topology;
  StrainGaugeParams gauge{};  // the DAD 141.1's settings, when it is the chain
  // The HSI's contact damping and the TOP's reference low-pass; empty: contact_settings', which replace the ones in
  // hsi_firmware and top_firmware as the gauge's calibration does.
  std::optional<double> hsi_contact_damping_nms;
  std::optional<double> top_reference_cutoff_hz;
  OperatorParams operator_params{};
  fw::LeverConfig hsi_firmware = default_firmware(protocol::Role::hsi);
  fw::LeverConfig top_firmware = default_firmware(protocol::Role::top);
  // Levers with incremental encoders power up at a random angle and home before the scenario; false: absolute
  // encoders at the operator's start angle (0.1 rad), armed at once.
  bool homing = true;
  EncoderInterface encoder_interface = EncoderInterface::gpio_events;
  int substeps = 10;  // physics steps per 1 ms tick
  double bitrate = 1e6;
  double bridge_latency_us = 100.0;  // each bridge's receive-to-send time (at least 1 us)
  double jnd = 0.10;                 // force_jnd_violation: relative threshold (Weber fraction)...
  double jnd_absolute_n = 0.05;      // ...but never below the absolute detection threshold for force
  bool record_trace = false;
  // With record_trace: each tick's row goes here as it is made (bounded memory), not into SimResult::trace.
  std::function<void(const TraceRow&)> trace_sink;
  std::function<void(const SimView&)> observer;  // called after every tick

  static fw::LeverConfig default_firmware(protocol::Role role);
};

// When a fault was injected and what each lever did about it.
struct FaultReport {
  FaultSpec spec;
  struct LeverReaction {
    std::optional<double> fault_at_s;    // entered the fault state
    std::uint16_t latched = 0;           // fault bits latched
    std::optional<double> safe_at_s;     // its safe behaviour was in force
    double max_torque_nm_during = 0.0;   // from injection to re-arm
    std::optional<double> rearmed_at_s;  // armed again
    bool armed_without_rearm = false;    // left the fault state for armed with no re-arm sent since: a bug
  } hsi, top;
};

struct TraceRow {
  double t, hsi_angle, top_angle, hsi_velocity, top_position_ref, contact_force, measured_force, displayed_force,
      hsi_torque, top_torque, hand_force;
  int motion_sent, force_sent, hsi_state, top_state;
};

struct SimResult {
  double velocity_packet_rate = 0.0;  // HSI data frames per tick while armed
  double force_packet_rate = 0.0;     // TOP data frames per tick while armed
  // The same frames by cause (fw::SendCause), adding up to the rates above: those the deadband rule alone sends
  // (the paper's count), the refreshes and the rest repeats the rule would not have sent.
  double velocity_deadband_rate = 0.0, velocity_refresh_rate = 0.0, velocity_rest_repeat_rate = 0.0;
  double force_deadband_rate = 0.0, force_refresh_rate = 0.0, force_rest_repeat_rate = 0.0;
  // Of the deadband's packets, those sent while the TOP touches the wall (its contact force above zero); the rest
  // were sent in free space. Per armed tick, as the rates above, so contact + free space = the deadband's rate.
  double velocity_deadband_contact_rate = 0.0, force_deadband_contact_rate = 0.0;
  double position_rmse_rad = 0.0;    // TOP angle against HSI angle
  double force_rmse_n = 0.0;         // displayed (HSI) against measured (TOP gauge)
  double force_jnd_violation = 0.0;  // share of armed ticks with |displayed - measured| > max(jnd |measured|, abs)
  // What the hand feels: its force on the HSI's handle against the TOP's measurement, RMS and by the same JND rule
  // (the displayed force above is the HSI's reconstruction, before its motor and the HSI's force loop).
  double hand_force_rmse_n = 0.0, hand_jnd_violation = 0.0;
  // The same by cause (RunMetrics::add_force_causes): displayed against the measurement one nominal delay
  // earlier; the codec alone; the prefilter alone.
  double force_jnd_violation_link = 0.0, force_jnd_violation_codec = 0.0, force_jnd_violation_filter = 0.0;
  int nominal_delay_ticks = 0;        // nominal_one_way_delay_ticks() of the run
  double prefilter_delay_ms = 0.0;    // the force prefilter's group delay at low frequencies, 1 / (2 pi f_c)
  double contact_share = 0.0;         // share of armed ticks the TOP touched the wall
  double mean_contact_force_n = 0.0;  // while in contact
  double contact_onsets_per_s = 0.0;  // the TOP's wall contact beginning, per armed second (RunMetrics)
  // Of those onsets, the ones within 30 ms of the last contact's end (a rebound), and the rebounds whose last
  // contact was a rebound too (RunMetrics): the chatter the contact check bounds.
  std::uint64_t contact_onsets = 0, contact_rebounds = 0, contact_rebounds_of_rebounds = 0;
  // Passivity (zero while off): what each lever's controller dissipated over the run (re-arms included), the lowest
  // observed energy seen while both were armed, and the energy frames both sent.
  double hsi_dissipated_energy_j = 0.0, top_dissipated_energy_j = 0.0;
  double hsi_min_observed_energy_j = 0.0, top_min_observed_energy_j = 0.0;
  std::uint64_t energy_frames = 0;
  // The levers' own protection tripping while the scenario ran (armed -> fault), injected faults included.
  struct LeverFaults {
    std::uint32_t count = 0;
    protocol::FaultBits bits = 0;  // every fault latched at those transitions
  } hsi_lever_faults, top_lever_faults;
  double bus_load_hsi = 0.0, bus_load_top = 0.0;
  std::uint64_t armed_ticks = 0;
  std::uint64_t motion_frames = 0, force_frames = 0;
  std::uint64_t network_sent = 0, network_lost = 0, network_reordered = 0;
  std::uint64_t hsi_seq_gaps = 0, top_seq_gaps = 0;
  double homed_at_s = 0.0;  // simulated time from power-up until both levers were homed and armed
  std::uint32_t hsi_overruns = 0, top_overruns = 0;
  std::uint64_t hsi_edges_lost = 0, top_edges_lost = 0;  // the encoder queue overflowed
  std::uint64_t refresh_frames = 0;                      // of motion_frames + force_frames, sent by the refresh
  double wall_time_s = 0.0;
  double realtime_factor = 0.0;
  std::vector<FaultReport> faults;
  std::vector<TraceRow> trace;
};

// The HSI's force display closed on its own strain gauge (the paper's force control loop, IV-A-1: the received
// force is the loop's set value), or open loop, the firmware's default.
void set_hsi_force_loop(SimConfig& config, bool on);
// Whether the HIL offers that loop on the run's gauge chain: not on the paper's, where it makes the contact chatter
// (docs/hil-model.md, "The HSI's force control loop"); run_simulation refuses it there.
bool hsi_force_loop_offered(const SimConfig& config);
// Throws std::invalid_argument for a setup the HIL does not offer (today: that loop where it is not offered). Every
// way of running the levers (run_simulation, HostedRig) asks it first.
void check_offered(const SimConfig& config);

// The ticks from a TOP's measurement to the HSI's display of it when nothing waits: a data frame's worst-case
// time on each bus, the bridges' latency and the network's configured delay (jitter not included), rounded up
// to the next tick, at which the receiving lever uses it.
int nominal_one_way_delay_ticks(const SimConfig& config);

SimResult run_simulation(const SimConfig& config);

}  // namespace lever::hil
