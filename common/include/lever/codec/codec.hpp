#pragma once
// The perceptual deadband codec: one include for users.
#include "lever/codec/config.hpp"
#include "lever/codec/prefilter.hpp"
#include "lever/codec/quantizer.hpp"
#include "lever/codec/receiver.hpp"
#include "lever/codec/reference_model.hpp"
#include "lever/codec/sender.hpp"
