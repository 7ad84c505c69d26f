#pragma once
// A lever's hardware for tests: an encoder, a strain gauge, a motor driver and a port on an in-memory CAN bus.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <utility>
#include <vector>

#include "lever/fw/hal.hpp"

namespace lever::test {

using fw::AbState;
using fw::EdgeDrain;
using fw::EncoderEdge;
using fw::ForceReading;
using fw::MotorCommand;
using protocol::CanFrame;

// Every frame sent is seen by every other port, as on a real bus; a port does not hear itself.
class CanBus {
 public:
  class Port {
   public:
    Port(CanBus& bus, std::size_t index) : bus_(&bus), index_(index) {}
    bool receive(CanFrame& frame) {
      auto& queue = bus_->rx_[index_];
      if (queue.empty()) return false;
      frame = queue.front();
      queue.pop_front();
      return true;
    }
    bool send(const CanFrame& frame) {
      if (bus_->tx_full) return false;
      bus_->log.push_back(frame);
      for (std::size_t i = 0; i < bus_->rx_.size(); ++i)
        if (i != index_ && !bus_->cut && frame.id != bus_->drop_id) bus_->rx_[i].push_back(frame);
      return true;
    }

   private:
    CanBus* bus_;
    std::size_t index_;
  };

  Port attach() {
    rx_.emplace_back();
    return Port(*this, rx_.size() - 1);
  }
  // A frame from outside any lever (a host, an attacker, a test).
  void inject(const CanFrame& frame) {
    for (auto& queue : rx_) queue.push_back(frame);
  }

  std::vector<CanFrame> log;
  bool cut = false;           // frames are sent but nobody receives them
  std::uint32_t drop_id = 0;  // frames with this id are sent but nobody receives them (0: none)
  bool tx_full = false;       // the controller's queue refuses frames

 private:
  std::vector<std::deque<CanFrame>> rx_;
};

// A hardware counter: the raw register value, wrapping at its width like a timer in encoder mode.
struct FakeEncoder {
  std::int32_t counts = 0;
  std::uint32_t width_mask = 0xFFFFFFFFu;
  std::uint32_t read_counts() const { return static_cast<std::uint32_t>(counts) & width_mask; }
};

// An edge source: queued edges, and losses it knows of, reported with the drain that reaches them.
struct FakeEdgeEncoder {
  std::vector<EncoderEdge> pending;
  std::uint32_t lost = 0;
  AbState current = 0;  // the levels after the newest edge delivered; at start, where the lines are
  void push(AbState levels, bool index = false) { pending.push_back({levels, index}); }
  AbState levels() const { return current; }
  EdgeDrain drain_edges(EncoderEdge* out, std::size_t capacity) {
    const std::size_t n = pending.size() < capacity ? pending.size() : capacity;
    for (std::size_t i = 0; i < n; ++i) out[i] = pending[i];
    if (n > 0) current = pending[n - 1].levels;
    pending.erase(pending.begin(), pending.begin() + static_cast<std::ptrdiff_t>(n));
    EdgeDrain d{n, 0};
    if (pending.empty()) d.lost = std::exchange(lost, 0u);
    return d;
  }
};

struct FakeForceSensor {
  std::optional<ForceReading> reading;
  std::optional<ForceReading> latest() const { return reading; }
};

struct FakeMotor {
  MotorCommand last;
  bool fault = false;
  double max_abs_torque = 0.0;  // over the whole test
  void command(const MotorCommand& c) {
    last = c;
    const double a = c.torque_nm < 0 ? -c.torque_nm : c.torque_nm;
    if (a > max_abs_torque) max_abs_torque = a;
  }
  bool driver_fault() const { return fault; }
};

template <typename Encoder = FakeEncoder>
struct FakeHal {
  explicit FakeHal(CanBus& bus) : can_(bus.attach()) {}
  Encoder encoder_;
  FakeForceSensor force_;
  FakeMotor motor_;
  CanBus::Port can_;
  Encoder& encoder() { return encoder_; }
  FakeForceSensor& force() { return force_; }
  FakeMotor& motor() { return motor_; }
  CanBus::Port& can() { return can_; }
};

static_assert(fw::LeverHal<FakeHal<FakeEncoder>>);
static_assert(fw::LeverHal<FakeHal<FakeEdgeEncoder>>);

}  // namespace lever::test
