// Instantiates every codec template the project uses, the elementary functions and the Gaussian draw, compiled with
// -fno-exceptions -fno-rtti. The object's undefined symbols are then checked (cmake/check_freestanding.sh): anything
// beyond sqrt, fabs and the memory-copy routines means the code reached libm, the heap, exceptions or the OS.
#include <cstdint>

#include "lever/codec/codec.hpp"
#include "lever/common/rng.hpp"
#include "lever/math/elementary.hpp"

namespace lever::codec {

template class DeadbandSender<float, 1>;
template class DeadbandSender<float, 3>;
template class DeadbandSender<double, 1>;
template class DeadbandSender<double, 3>;
template class DeadbandSender<float, 1, FixedPointQuantizer<float, std::int16_t>>;
template class DeadbandSender<float, 3, FixedPointQuantizer<float, std::int16_t>>;
template class DeadbandSender<double, 1, FixedPointQuantizer<double, std::int32_t>>;
template class DeadbandSender<double, 3, FixedPointQuantizer<double, std::int32_t>>;
template class DeadbandReceiver<float, 1>;
template class DeadbandReceiver<float, 3>;
template class DeadbandReceiver<double, 1>;
template class DeadbandReceiver<double, 3>;
template class DeadbandReceiver<float, 1, FixedPointQuantizer<float, std::int16_t>>;
template class DeadbandReceiver<float, 3, FixedPointQuantizer<float, std::int16_t>>;
template class DeadbandReceiver<double, 1, FixedPointQuantizer<double, std::int32_t>>;
template class DeadbandReceiver<double, 3, FixedPointQuantizer<double, std::int32_t>>;

}  // namespace lever::codec

namespace lever::freestanding {

// The elementary functions and the Gaussian draw call no libm routine but sqrt: that is their point.
double elementary(double x) { return math::exp(x) + math::log(x) + math::sin(x) + math::cos(x) + math::acos(x); }
double gaussian(Rng& rng) { return rng.normal(); }

}  // namespace lever::freestanding
