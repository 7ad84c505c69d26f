#pragma once
// A snapshot as one JSON object: lever-view --json prints one a refresh, for scripts and tests (docs/lever-view.md
// names every field).
#include <nlohmann/json.hpp>

#include "pair_monitor.hpp"
#include "screen_text.hpp"

namespace lever::view {

nlohmann::json to_json(const Snapshot& snapshot, const ReaderState& reader);

}  // namespace lever::view
