#pragma once
// The paper's 3-DoF experiment (section IV-B): an Omni-like 3-DoF haptic device in an operator's hand sends
// position and velocity over a LAN to a virtual environment holding one sphere, which sends the force of
// eq. (11) back. No lever and no firmware: the codec (lever::codec, N = 3) is driven directly, as the paper's
// PCs did. Deterministic: the same configuration and seed give the same run, bit for bit.
// docs/hil-model.md ("sphere-3dof") gives every parameter's reason.
#include <cstdint>
#include <functional>
#include <string_view>
#include <vector>

#include "lever/codec/config.hpp"
#include "lever/codec/quantizer.hpp"
#include "lever/common/vec.hpp"
#include "lever/hil/network.hpp"

namespace lever::hil {

using Vec3 = Vec<double, 3>;

// The SensAble PHANTOM Omni as its data sheet gives it.
struct OmniParams {
  double resolution_m = 55e-6;              // nominal position resolution (> 450 dpi): the cartesian-grid sensor's cell
  double encoder_counts_per_rev = 15000.0;  // each of the three base joints' encoders (the Omni's drivers)
  double link_m = 0.13335;                  // upper arm and forearm (Jarillo-Silva et al. 2009)
  double max_force_n = 3.3;                 // maximum exertable force: the displayed vector's magnitude saturates here
  double mass_kg = 0.045;                   // apparent mass at the tip
  double friction_n = 0.26;                 // backdrive friction (the data sheet's bound)
  double friction_linear_mps = 0.002;       // below this speed friction grows linearly: no chatter at the step
};

// The operator's hand and arm on the stylus, and what the person does with them.
struct HandParams {
  double mass_kg = 0.3;         // hand and forearm, as the 1-DoF operator (docs/hil-model.md)
  double stiffness = 300.0;     // N/m: a relaxed grip
  double damping = 20.0;        // N s/m: near critical with the hand's and the device's mass
  double tremor_rms_m = 50e-6;  // physiological tremor, 3-D rms displacement of the free hand
  double tremor_low_hz = 8.0, tremor_high_hz = 12.0;
  int tremor_components = 6;  // sinusoids per axis, frequencies drawn in the band
  bool explore = true;        // false: the hand holds still where it starts (tests)
  // Exploring: strokes over the sphere at a light force, presses, lifting off and coming down elsewhere.
  double stroke_force_min_n = 0.5, stroke_force_max_n = 1.5;
  double press_force_min_n = 1.5, press_force_max_n = 3.0;
  double stroke_speed_min_mps = 0.02, stroke_speed_max_mps = 0.08;
  double lift_min_m = 0.005, lift_max_m = 0.015;
  double cap_half_angle_rad = 1.0471975511965976;  // 60 degrees around +z, the side facing the user
};

// The virtual environment's only object.
struct SphereParams {
  Vec3 centre{};              // m: the middle of the workspace
  double radius_m = 0.025;    // fits the Omni's 70 mm workspace depth with room around it
  double stiffness = 1000.0;  // N/m, u of eq. (11): about the Omni's stiffest axis-wise bound (Z, 1.02 N/mm)
};

// How the OP reads the device's velocity (docs/hil-model.md): as the PHANToM Omni ROS driver gives it (a second-order
// backward difference and a third-order Butterworth low-pass), or the one-tick difference of the quantized position.
enum class SphereVelocityChain : std::uint8_t { driver, difference };
inline constexpr SphereVelocityChain kAllVelocityChains[] = {SphereVelocityChain::driver,
                                                             SphereVelocityChain::difference};
constexpr std::string_view name(SphereVelocityChain c) {
  return c == SphereVelocityChain::driver ? "driver" : "difference";
}

// How the OP reads the tip's position (docs/hil-model.md, "The position as the Omni measures it"): as the Omni does,
// three joint encoders and the kinematics, in doubles; or, for comparison, quantized on a Cartesian grid of the data
// sheet's resolution (the model before issue 33); or, as a diagnostic that is no device's chain, the tip's exact
// position, unquantized.
enum class SpherePositionSensor : std::uint8_t { joint_encoders, cartesian_grid, exact };
inline constexpr SpherePositionSensor kAllPositionSensors[] = {
    SpherePositionSensor::joint_encoders, SpherePositionSensor::cartesian_grid, SpherePositionSensor::exact};
constexpr std::string_view name(SpherePositionSensor s) {
  return s == SpherePositionSensor::joint_encoders   ? "joint-encoders"
         : s == SpherePositionSensor::cartesian_grid ? "cartesian-grid"
                                                     : "exact";
}

// How the two PCs keep time (docs/hil-model.md, "The teleoperator's own clock"): the TOP on its own 1 kHz clock, at
// a phase and a drift drawn per seed, each side applying a packet when it arrives and evaluating the sender's model
// over its own time elapsed since; or, the model before issue 39, the TOP on the OP's clock the link's nominal delay
// late with play-out queues at both receivers.
enum class SphereTopClock : std::uint8_t { own, op_playout };
inline constexpr SphereTopClock kAllTopClocks[] = {SphereTopClock::own, SphereTopClock::op_playout};
constexpr std::string_view name(SphereTopClock clock) { return clock == SphereTopClock::own ? "own" : "op-playout"; }

struct SphereTraceRow {
  double t = 0.0;
  Vec3 position{};  // the device's tip (true)
  Vec3 measured{};  // as the device measures it (position_sensor)
  Vec3 velocity{};  // the velocity the OP reads (its chain on measured), the value offered to the codec
  bool velocity_sent = false;
  bool top_has_position = false;
  Vec3 top_position{};       // the TOP's extrapolated user position
  Vec3 environment_force{};  // eq. (11) at top_position
  bool force_sent = false;
  Vec3 displayed_force{};  // what the device displays (reconstructed, saturated)
  Vec3 reference_force{};  // the force the undistorted system (p = 0, lossless) would display now
};

struct SphereConfig {
  double duration_s = 30.0;  // the paper's interval length in IV-B
  std::uint64_t seed = 1;
  codec::Config<double> velocity_codec{codec::Mode::deadband, 0.0, 0.0, 0.0};  // OP -> TOP
  codec::Config<double> force_codec{codec::Mode::deadband, 0.0, 0.0, 0.0};     // TOP -> OP
  // A switched 100 Mbit/s Ethernet LAN; it never reorders (reorder is ignored: the LAN is FIFO).
  NetworkParams network{0.2, 0.1, 0.0, false};
  OmniParams device{};
  SpherePositionSensor position_sensor = SpherePositionSensor::joint_encoders;
  SphereVelocityChain velocity_chain = SphereVelocityChain::driver;
  double driver_cutoff_hz = 20.0;  // the driver's low-pass (the ROS driver's 20 Hz)
  SphereTopClock top_clock = SphereTopClock::own;
  // The TOP's clock against the OP's, drawn per seed with top_clock own: a drift uniform in +-this (two PC clocks
  // of +-100 ppm each) and a phase uniform in [0, 1 ms).
  double top_clock_drift_ppm_max = 200.0;
  HandParams hand{};
  SphereParams sphere{};
  double jnd = 0.1;              // Weber fraction of the distortion metric
  double jnd_absolute_n = 0.05;  // its absolute floor, as the 1-DoF metric
  int substeps = 10;             // physics steps per 1 ms tick
  bool record_trace = false;
  // With record_trace: each tick's row goes here as it is made (bounded memory), not into SphereResult::trace.
  std::function<void(const SphereTraceRow&)> trace_sink;
};

// The paper's variants: a deadband on one direction at a time, the other sending every change (p = 0, which
// the receiver reconstructs exactly as if every sample had been sent).
enum class SphereDirection : std::uint8_t { velocity, force };
// Prefilter cut-offs of the "+ filter" variants, per direction (docs/hil-model.md says why).
inline constexpr double kSphereVelocityFilterHz = 10.0;
inline constexpr double kSphereForceFilterHz = 30.0;
SphereConfig sphere_variant(SphereDirection direction, codec::Mode mode, bool filter, double p);

struct SphereResult {
  std::uint64_t ticks = 0;
  std::uint64_t velocity_packets = 0, force_packets = 0;
  double velocity_packet_rate = 0.0;  // packets per 1 kHz sample
  double force_packet_rate = 0.0;
  // Of those, the packets sent on ticks the environment's force is not zero (in contact); the rest in free space.
  double velocity_contact_rate = 0.0, force_contact_rate = 0.0;
  double contact_share = 0.0;  // share of ticks with a non-zero environment force
  double mean_contact_force_n = 0.0;
  double saturated_share = 0.0;  // share of ticks the environment asked for more than the device's peak
  // Share of ticks with |displayed - reference| > max(jnd |reference|, floor). The reference is the undistorted
  // system's force: eq. (11) at the measured position the link's round trip earlier (both directions' codecs).
  double force_jnd_violation = 0.0;
  double force_rmse_n = 0.0;  // displayed against that reference
  // The same against the force the TOP computed, the downlink's delay earlier: the force direction's codec alone.
  double downlink_jnd_violation = 0.0;
  double position_rmse_m = 0.0;  // the TOP's position against the measured one, the link's delay earlier
  double position_max_error_m = 0.0;
  double zero_velocity_share = 0.0;  // samples whose differenced velocity is exactly zero
  double mean_speed_mps = 0.0;       // the device's true speed
  int uplink_delay_ticks = 0;        // the link's nominal delay, OP -> TOP and TOP -> OP, in ticks
  int downlink_delay_ticks = 0;
  std::uint64_t stale_packets = 0;  // arrived after a newer one (dropped)
  // The TOP's clock as drawn (zero with op_playout): its first tick's time on the OP's clock, and its drift.
  double top_clock_phase_ms = 0.0, top_clock_drift_ppm = 0.0;
  std::uint64_t top_ticks = 0;
  double realtime_factor = 0.0;
  double wall_time_s = 0.0;
  std::vector<SphereTraceRow> trace;
};

// 16 bits per DoF on the link (the paper's section I; docs/hil-model.md, "16 bits per DoF on the wire"): each
// component a 16-bit integer, rounded to nearest, clipped at its range. The position at 5 um (+-164 mm, a tenth of an
// encoder count at the tip; on the cartesian grid at the grid's own step, which goes over exactly), the velocity at
// 0.1 mm/s (+-3.28 m/s), the force at the device's peak over 32767.
using SphereWire = codec::FixedPointQuantizer<double, std::int16_t>;
inline SphereWire sphere_position_wire(const SphereConfig& c) {
  return {c.position_sensor == SpherePositionSensor::cartesian_grid ? c.device.resolution_m : 5e-6};
}
inline SphereWire sphere_velocity_wire() { return {1e-4}; }
inline SphereWire sphere_force_wire(const OmniParams& device) { return {device.max_force_n / 32767.0}; }

// Eq. (11): zero outside the sphere (and at its centre), else u (r - |x - s|) along (x - s)/|x - s|.
Vec3 sphere_force(const SphereParams& sphere, const Vec3& x);

// Throws std::invalid_argument on an invalid configuration.
SphereResult run_sphere(const SphereConfig& config);

}  // namespace lever::hil
