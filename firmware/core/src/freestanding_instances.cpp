// Instantiates the lever core for both roles and both encoder flavours with a minimal HAL, compiled -fno-exceptions
// -fno-rtti; cmake/check_freestanding.sh then proves the object needs no heap, exceptions or OS.
#include <cstddef>
#include <optional>

#include "lever/fw/lever.hpp"

namespace lever::fw::freestanding {

struct EdgeEncoder {
  EdgeDrain drain_edges(EncoderEdge*, std::size_t) { return {}; }
  AbState levels() const { return 0; }
};
struct CountingEncoder {
  std::uint32_t read_counts() { return 0; }
};
struct Force {
  std::optional<ForceReading> latest() { return std::nullopt; }
};
struct Motor {
  void command(const MotorCommand&) {}
  bool driver_fault() const { return false; }
};
struct Can {
  bool receive(protocol::CanFrame&) { return false; }
  bool send(const protocol::CanFrame&) { return true; }
};

template <typename Encoder>
using Hal = Ports<Encoder, Force, Motor, Can>;

}  // namespace lever::fw::freestanding

namespace fs = lever::fw::freestanding;
template class lever::fw::Lever<fs::Hal<fs::EdgeEncoder>, lever::fw::HsiRole>;
template class lever::fw::Lever<fs::Hal<fs::EdgeEncoder>, lever::fw::TopRole>;
template class lever::fw::Lever<fs::Hal<fs::CountingEncoder>, lever::fw::HsiRole>;
template class lever::fw::Lever<fs::Hal<fs::CountingEncoder>, lever::fw::TopRole>;
