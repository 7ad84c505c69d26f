#pragma once
// Why a data frame goes out. The paper's senders send what the deadband rule decides and nothing else; this link
// also forces frames, so that a lost one heals. A frame is the rule's when the rule alone sends its sample, forced
// or not; else it is a refresh (the period, a restart, a reconfiguration) or the repeat of a frame that brought its
// stream to rest.
#include <cstdint>

namespace lever::fw {

enum class SendCause : std::uint8_t { deadband, refresh, rest_repeat };

}  // namespace lever::fw
