#pragma once
// The names lever-hil's options take, each with the value it stands for.
#include "lever/fw/lever_config.hpp"
#include "lever/hil/human_operator.hpp"
#include "lever/hil/simulation.hpp"
#include "lever/hil/sphere3dof.hpp"
#include "lever/program/choices.hpp"
#include "scenario_option.hpp"
#include "sweep.hpp"

namespace lever::hil {

// Each from its enum's own table and names, next to the type.
inline const program::Choices<ScenarioOption> kScenarios = program::choices_of(kAllScenarioOptions);
inline const program::Choices<Topology> kTopologies = program::choices_of(kAllTopologies);
inline const program::Choices<fw::MotionVelocity> kMotionVelocities = program::choices_of(fw::kAllMotionVelocities);
inline const program::Choices<SphereVelocityChain> kDeviceVelocities = program::choices_of(kAllVelocityChains);
inline const program::Choices<SpherePositionSensor> kPositionSensors = program::choices_of(kAllPositionSensors);
inline const program::Choices<SphereTopClock> kTopClocks = program::choices_of(kAllTopClocks);
inline const program::Choices<GaugeChain> kGaugeChains = program::choices_of(kAllGaugeChains);
inline const program::Choices<bool> kOnOff{{"on", true}, {"off", false}};
inline const program::Choices<EncoderInterface> kEncoderInterfaces = program::choices_of(kAllEncoderInterfaces);
inline const program::Choices<SweepAxis> kSweepAxes{{"p", SweepAxis::p}, {"delay", SweepAxis::delay}};
inline const program::Choices<fw::PassivityMode> kPassivity = program::choices_of(fw::kAllPassivityModes);

}  // namespace lever::hil
