#pragma once
// The two levers lever-hil serve plays for: their lever-fw configurations, loaded and checked to be an HSI and a
// TOP of one pair, and the simulated world's configuration they imply.
#include <optional>

#include "lever/app/fw_config.hpp"
#include "lever/hil/simulation.hpp"
#include "serve.hpp"

namespace lever::hil {

struct ServePair {
  app::FwConfig hsi, top;
};

// None when a file is not a valid configuration or the two are not an HSI and a TOP of one pair (said on stderr).
std::optional<ServePair> load_serve_pair(const ServeOptions& o);

// The same physical world as lever-hil run, with the levers' own codecs and firmware.
SimConfig serve_sim_config(const ServeOptions& o, const ServePair& pair);

}  // namespace lever::hil
