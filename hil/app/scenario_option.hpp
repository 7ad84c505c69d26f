#pragma once
// What lever-hil's --scenario names: one of the levers' scenarios (ScenarioKind, the lever simulator's) or
// sphere-3dof, the paper's 3-DoF experiment, which has no levers and runs on a simulator of its own
// (lever/hil/sphere3dof.hpp). The lever simulator knows nothing of the sphere; the commands dispatch on this.
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <optional>
#include <string_view>

#include "lever/hil/human_operator.hpp"

namespace lever::hil {

// A lever scenario's value is its ScenarioKind's; the sphere comes after them.
enum class ScenarioOption : std::uint8_t { wall_tap, free_motion, press_hold, sphere_3dof };
inline constexpr ScenarioOption kAllScenarioOptions[] = {ScenarioOption::wall_tap, ScenarioOption::free_motion,
                                                         ScenarioOption::press_hold, ScenarioOption::sphere_3dof};

// The lever scenario the option names; empty for sphere-3dof.
constexpr std::optional<ScenarioKind> lever_scenario(ScenarioOption s) {
  if (s == ScenarioOption::sphere_3dof) return std::nullopt;
  return static_cast<ScenarioKind>(static_cast<std::uint8_t>(s));
}

constexpr std::string_view name(ScenarioOption s) {
  const auto lever = lever_scenario(s);
  return lever ? name(*lever) : "sphere-3dof";
}

// A lever scenario added to ScenarioKind needs its option here, by the same value, before the sphere.
static_assert([] {
  if (std::size(kAllScenarioOptions) != std::size(kAllScenarios) + 1) return false;
  for (std::size_t i = 0; i < std::size(kAllScenarios); ++i)
    if (lever_scenario(kAllScenarioOptions[i]) != kAllScenarios[i]) return false;
  return !lever_scenario(kAllScenarioOptions[std::size(kAllScenarios)]);
}());

}  // namespace lever::hil
