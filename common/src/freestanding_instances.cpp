// Instantiates every codec template the project uses, compiled with -fno-exceptions -fno-rtti. The object's
// undefined symbols are then checked (cmake/check_freestanding.sh): anything beyond a short list of libm
// and memory-copy routines means the code reached the heap, exceptions or the OS.
#include <cstdint>

#include "lever/codec/codec.hpp"

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
