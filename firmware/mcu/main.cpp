// The lever core on a Cortex-M7 with a stand-in HAL. LEVER_MCU_ROLE selects what the image holds: `hsi` or
// `top` alone (one controller's firmware, for its flash and RAM), or `pair`: both levers on an in-memory bus
// with a small plant, run for a few simulated seconds under QEMU as a smoke test that arms them and moves data
// both ways, reporting through semihosting.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>

#include "lever/fw/lever.hpp"
#include "semihosting.hpp"

namespace {

using namespace lever;

// A memory-mapped peripheral stands in for each port: the core cannot know the value at compile time.
struct Encoder {
  volatile std::uint32_t* counter;
  std::uint32_t read_counts() { return *counter; }
};
struct Force {
  volatile std::int32_t* adc;
  volatile std::uint32_t* stamp;
  std::optional<fw::ForceReading> latest() { return fw::ForceReading{static_cast<double>(*adc), *stamp, false}; }
};
struct Motor {
  volatile std::int32_t* duty;
  volatile std::uint32_t* fault_line;
  double last = 0.0;
  void command(const fw::MotorCommand& c) {
    last = c.enable ? c.torque_nm : 0.0;
    *duty = static_cast<std::int32_t>(last * 1000.0);
  }
  bool driver_fault() const { return *fault_line != 0; }
};

// A mailbox of frames from the other controller (a CAN controller's receive FIFO).
struct Fifo {
  protocol::CanFrame frames[32];
  std::size_t head = 0, count = 0;
  bool push(const protocol::CanFrame& f) {
    if (count == 32) return false;
    frames[(head + count++) % 32] = f;
    return true;
  }
  bool pop(protocol::CanFrame& f) {
    if (count == 0) return false;
    f = frames[head];
    head = (head + 1) % 32;
    --count;
    return true;
  }
};
struct Can {
  Fifo* rx;
  Fifo* tx;
  bool receive(protocol::CanFrame& f) { return rx->pop(f); }
  bool send(const protocol::CanFrame& f) { return tx->push(f); }
};

using Hal = fw::Ports<Encoder, Force, Motor, Can>;
static_assert(fw::LeverHal<Hal>);

// Registers: plain memory on QEMU, peripherals on a board.
volatile std::uint32_t counters[2], stamps[2], faults[2];
volatile std::int32_t adcs[2], duties[2];

fw::LeverConfig config_for(protocol::Role role) {
  fw::LeverConfig c;
  c.role = role;
  c.use_force_sensor = role == protocol::Role::top;
  c.homing.method = fw::HomingMethod::absolute;
  return c;
}

Hal hal_for(int i, Fifo& rx, Fifo& tx) {
  return Hal{{&counters[i]}, {&adcs[i], &stamps[i]}, {&duties[i], &faults[i], 0.0}, {&rx, &tx}};
}

struct Plant {
  double angle = 0.0, speed = 0.0;
  void advance(double torque) {
    speed += (torque - 0.02 * speed) / 2e-3 * 1e-3;
    angle += speed * 1e-3;
  }
};

#if defined(LEVER_MCU_PAIR)
int run() {
  static Fifo to_hsi, to_top;
  static Hal hsi_hal = hal_for(0, to_hsi, to_top), top_hal = hal_for(1, to_top, to_hsi);
  static fw::HsiLever<Hal> hsi(hsi_hal, config_for(protocol::Role::hsi));
  static fw::TopLever<Hal> top(top_hal, config_for(protocol::Role::top));
  Plant hsi_plant, top_plant;
  const double count = 2.0 * 3.14159265358979 / 16384.0;
  constexpr fw::Tick kTicks = 5000;
  for (fw::Tick now = 1; now <= kTicks; ++now) {
    if (now == 100) {
      const auto arm = protocol::pack(protocol::CommandMessage{}, 0);
      to_hsi.push(arm);
      to_top.push(arm);
    }
    // The hand pulls the HSI toward 0.25 rad, the TOP follows into a wall at 0.2 rad.
    const double wall = top_plant.angle > 0.2 ? 200.0 * (top_plant.angle - 0.2) : 0.0;
    hsi_plant.advance(3.0 * (0.25 - hsi_plant.angle) - 0.15 * hsi_plant.speed + hsi_hal.motor_.last);
    top_plant.advance(top_hal.motor_.last - wall);
    counters[0] = static_cast<std::uint32_t>(static_cast<std::int32_t>(std::floor(hsi_plant.angle / count)));
    counters[1] = static_cast<std::uint32_t>(static_cast<std::int32_t>(std::floor(top_plant.angle / count)));
    adcs[1] = static_cast<std::int32_t>(wall / 0.1 / (100.0 / 65536.0));
    stamps[1] = static_cast<std::uint32_t>(now);
    hsi.step(now);
    top.step(now);
  }
  const bool armed = hsi.supervisor().armed() && top.supervisor().armed();
  const bool both_ways = hsi.counters().data_sent > 0 && top.counters().data_sent > 0 && hsi.counters().rx_frames > 0 &&
                         top.counters().rx_frames > 0;
  const bool followed = std::fabs(top_plant.angle - 0.2) < 0.05;
  mcu::write("lever-mcu: ");
  mcu::write_number(kTicks);
  mcu::write(" ticks; armed ");
  mcu::write(armed ? "yes" : "no");
  mcu::write("; motion frames ");
  mcu::write_number(hsi.counters().data_sent);
  mcu::write(", force frames ");
  mcu::write_number(top.counters().data_sent);
  mcu::write("; TOP at the wall ");
  mcu::write(followed ? "yes" : "no");
  mcu::write("; bytes per lever: HSI ");
  mcu::write_number(sizeof hsi);
  mcu::write(", TOP ");
  mcu::write_number(sizeof top);
  mcu::write("\n");
  return armed && both_ways && followed ? 0 : 1;
}
#else
template <typename Role>
int run() {
  // Static storage, so the image's RAM figure includes the lever's state.
  static Fifo rx, tx;
  static Hal hal = hal_for(0, rx, tx);
  static fw::Lever<Hal, Role> lever(hal, config_for(Role::kRole));
  for (fw::Tick now = 1;; ++now) {
    stamps[0] = static_cast<std::uint32_t>(now);
    lever.step(now);
    if (now == 1000) break;
  }
  return lever.supervisor().state() == fw::LeverState::disarmed ? 0 : 1;
}
#endif

}  // namespace

int main() {
#if defined(LEVER_MCU_PAIR)
  const int rc = run();
#elif defined(LEVER_MCU_HSI)
  const int rc = run<fw::HsiRole>();
#else
  const int rc = run<fw::TopRole>();
#endif
  lever::mcu::exit(rc == 0);
}
