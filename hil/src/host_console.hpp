#pragma once
// The operator console at the HSI's site, as lever-hil run models it: it homes and arms both levers after power-up
// and, once injected faults are over, re-homes and re-arms the ones that need it, by command frames on the bus.
#include <cstdint>

#include "lever/hil/can_bus.hpp"
#include "lever/protocol/messages.hpp"
#include "sim_levers.hpp"

namespace lever::hil {

class HostConsole {
 public:
  HostConsole(CanBus& bus, std::uint8_t pair, const Nanos& now)
      : bus_(bus), node_(bus.add_node()), pair_(pair), now_(now) {}

  // Looks at the levers every 100 ms: before the scenario (`start` 0) 50 ms into each period, once heartbeats
  // have flowed; in it from the scenario's start, unless injected faults hold it back.
  void step(fw::Tick tick, fw::Tick start, bool faults_hold, SimLevers& levers);

  // A program at the console (HostedRig): it sends from the console's node and reads every frame the node
  // receives, as another process on the same bus would.
  bool send(const protocol::CanFrame& frame) { return bus_.send(node_, frame, now_); }
  bool receive(TimedFrame& frame) { return bus_.receive(node_, frame); }

 private:
  void manage(SimLevers& levers);
  void send(protocol::Opcode opcode, bool to_hsi, bool to_top, SimLevers& levers);

  CanBus& bus_;
  CanBus::Node node_;
  std::uint8_t pair_;
  const Nanos& now_;
};

}  // namespace lever::hil
