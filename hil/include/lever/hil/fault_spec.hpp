#pragma once
// Fault injection specs, as typed on the command line: KIND@START[+DURATION][:ARG]
//   link-down@5+0.5        the IP link drops every datagram for 0.5 s from t = 5 s
//   burst-loss@5+0.3       half the datagrams are lost for 0.3 s
//   delay-step@5:40        the one-way delay grows by 40 ms from t = 5 s (for DURATION if given)
//   bus-off@5+0.2:top      the TOP's CAN controller is bus-off (ARG: hsi or top, default top)
//   encoder-glitch@5+0.01:hsi  illegal A/B transitions every tick
//   gauge-stale@5+0.5      the TOP's amplifier stops delivering samples
//   gauge-saturated@5+0.5  the TOP's amplifier reads at its limit
//   motor-fault@5+0.5:top  the motor driver reports a fault
//   tick-late@5+0.02:top   the lever's firmware is not stepped for 20 ms (a scheduling hiccup); the motor keeps
//                          its last command meanwhile, as a PWM output does
//   reboot@5+0.2:hsi       the lever's controller restarts: silent with its motor disabled for DURATION
//                          (default 0: back at once), then from power-up state, ticks and sequence numbers
//                          included; the host homes it and re-arms the pair
#include <cstdint>
#include <string>
#include <string_view>

namespace lever::hil {

enum class FaultKind : std::uint8_t {
  link_down,
  burst_loss,
  delay_step,
  bus_off,
  encoder_glitch,
  gauge_stale,
  gauge_saturated,
  motor_fault,
  tick_late,
  reboot,
};

enum class Site : std::uint8_t { hsi, top };

struct FaultSpec {
  FaultKind kind = FaultKind::link_down;
  double start_s = 0.0;
  double duration_s = 0.5;  // delay-step without +DURATION: until the end of the run
  Site site = Site::top;
  double value = 0.0;  // delay-step: extra milliseconds
  std::string text;    // as given, for reports
};

// Throws std::invalid_argument with a message naming the problem.
FaultSpec parse_fault_spec(std::string_view text);
std::string_view to_string(FaultKind kind);

}  // namespace lever::hil
