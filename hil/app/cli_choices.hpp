#pragma once
// The names lever-hil's options take, each with the value it stands for.
#include "lever/codec/config.hpp"
#include "lever/fw/lever_config.hpp"
#include "lever/hil/human_operator.hpp"
#include "lever/hil/simulation.hpp"
#include "lever/hil/sphere3dof.hpp"
#include "lever/program/choices.hpp"
#include "sweep.hpp"

namespace lever::hil {

inline const program::Choices<ScenarioKind> kScenarios{{"wall-tap", ScenarioKind::wall_tap},
                                                       {"free-motion", ScenarioKind::free_motion},
                                                       {"press-hold", ScenarioKind::press_hold},
                                                       {"sphere-3dof", ScenarioKind::sphere_3dof}};
inline const program::Choices<Topology> kTopologies{
    {"one-controller", Topology::one_controller}, {"one-site", Topology::one_site}, {"two-sites", Topology::two_sites}};
inline const program::Choices<fw::MotionVelocity> kMotionVelocities{
    {"difference", fw::MotionVelocity::difference},
    {"adaptive-window", fw::MotionVelocity::adaptive_window},
    {"estimate", fw::MotionVelocity::estimate}};
inline const program::Choices<SphereVelocityChain> kDeviceVelocities{{"driver", SphereVelocityChain::driver},
                                                                     {"difference", SphereVelocityChain::difference}};
inline const program::Choices<SpherePositionSensor> kPositionSensors{
    {"joint-encoders", SpherePositionSensor::joint_encoders},
    {"cartesian-grid", SpherePositionSensor::cartesian_grid},
    {"exact", SpherePositionSensor::exact}};
inline const program::Choices<SphereTopClock> kTopClocks = program::choices_of(kAllTopClocks, name);
inline const program::Choices<GaugeChain> kGaugeChains{
    {"topology", GaugeChain::topology}, {"dad141", GaugeChain::dad141}, {"paper-adc", GaugeChain::paper_adc}};
inline const program::Choices<bool> kOnOff{{"on", true}, {"off", false}};
inline const program::Choices<EncoderInterface> kEncoderInterfaces{{"gpio-events", EncoderInterface::gpio_events},
                                                                   {"counter", EncoderInterface::counter}};
inline const program::Choices<SweepAxis> kSweepAxes{{"p", SweepAxis::p}, {"delay", SweepAxis::delay}};
inline const program::Choices<fw::PassivityMode> kPassivity{
    {"off", fw::PassivityMode::off}, {"observe", fw::PassivityMode::observe}, {"tdpa", fw::PassivityMode::tdpa}};
inline const program::Choices<codec::Mode> kModes = program::choices_of(codec::kAllModes, codec::name);

}  // namespace lever::hil
