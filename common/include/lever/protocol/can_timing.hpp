#pragma once
// How long a classic CAN frame occupies the bus: used by the HIL's bus model and the bridge's bus-load figure.

namespace lever::protocol {

// Bits of a classic 11-bit-id data frame with the worst-case stuffing: SOF to IFS is 47 + 8n bits, of which
// the 34 + 8n before the CRC delimiter may carry a stuff bit after every four equal bits.
constexpr int frame_bits_worst_case(int dlc) noexcept { return 47 + 8 * dlc + (34 + 8 * dlc - 1) / 4; }

}  // namespace lever::protocol
