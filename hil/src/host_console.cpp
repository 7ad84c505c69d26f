#include "host_console.hpp"

namespace lever::hil {
namespace {
constexpr fw::Tick kHostPeriod = 100;  // the host looks at the levers every 100 ms
}

void HostConsole::step(fw::Tick tick, fw::Tick start, bool faults_hold, SimLevers& levers) {
  if (start == 0) {
    if (tick % kHostPeriod == 50) manage(levers);  // heartbeats have flowed for 50 ms by then
  } else if ((tick - start) % kHostPeriod == 0 && !faults_hold) {
    manage(levers);
  }
}

// Home a lever whose position is unknown; once neither needs homing, re-arm the ones that are not armed, so that
// the pair starts together. A lever in fault takes no home: the host acknowledges the fault with a disarm first
// (docs/can-protocol.md, "What clears a fault").
void HostConsole::manage(SimLevers& levers) {
  const bool hsi_home = levers.hsi().needs_homing(), top_home = levers.top().needs_homing();
  send(protocol::Opcode::disarm, hsi_home && levers.hsi().state() == fw::LeverState::fault,
       top_home && levers.top().state() == fw::LeverState::fault, levers);
  send(protocol::Opcode::home, hsi_home, top_home, levers);
  const bool homing = hsi_home || top_home || levers.hsi().state() == fw::LeverState::homing ||
                      levers.top().state() == fw::LeverState::homing;
  if (!homing) send(protocol::Opcode::rearm, levers.hsi().needs_arming(), levers.top().needs_arming(), levers);
}

void HostConsole::send(protocol::Opcode opcode, bool to_hsi, bool to_top, SimLevers& levers) {
  if (!to_hsi && !to_top) return;
  protocol::CommandMessage m;
  m.opcode = opcode;
  m.to_hsi = to_hsi;
  m.to_top = to_top;
  bus_.send(node_, protocol::pack(m, pair_), now_);
  if (opcode == protocol::Opcode::rearm) {
    levers.hsi().rearms_sent += to_hsi;
    levers.top().rearms_sent += to_top;
  }
}

}  // namespace lever::hil
