#pragma once
// The one way fault bits become text on a host (logs, views, reports, JSON). Hosted only: the firmware core never
// spells a fault, it sends the bits (faults.hpp stays freestanding).
#include <string>
#include <string_view>
#include <vector>

#include "lever/protocol/faults.hpp"

namespace lever::protocol {

// Bits that no Fault names: a newer lever's fault must show as something, never vanish from a list.
constexpr FaultBits unknown_fault_bits(FaultBits bits) noexcept {
  FaultBits known = 0;
  for (const Fault f : kAllFaults) known = static_cast<FaultBits>(known | bit(f));
  return static_cast<FaultBits>(bits & ~known);
}

// Each set fault's name in kAllFaults order, then "unknown bits 0xNNNN" if any.
inline std::vector<std::string> fault_name_list(FaultBits bits) {
  std::vector<std::string> names;
  for (const Fault f : kAllFaults)
    if (has(bits, f)) names.emplace_back(name(f));
  if (const FaultBits unknown = unknown_fault_bits(bits); unknown != 0) {
    constexpr std::string_view digits = "0123456789abcdef";
    std::string hex = "unknown bits 0x";
    for (int shift = 12; shift >= 0; shift -= 4) hex += digits[(unknown >> shift) & 0xFu];
    names.push_back(std::move(hex));
  }
  return names;
}

// fault_name_list joined by `separator`; `none` when no bit is set.
inline std::string fault_names(FaultBits bits, std::string_view separator, std::string_view none = "") {
  std::string out;
  for (const std::string& n : fault_name_list(bits)) {
    if (!out.empty()) out += separator;
    out += n;
  }
  return out.empty() ? std::string(none) : out;
}

}  // namespace lever::protocol
