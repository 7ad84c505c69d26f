#include "can_reader.hpp"

#include <poll.h>

#include <array>
#include <chrono>
#include <ctime>
#include <utility>

namespace lever::view {

std::int64_t realtime_us() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000 + ts.tv_nsec / 1000;
}

CanReader::CanReader(board::SocketCan can, LiveMonitor& live)
    : can_(std::move(can)), live_(live), thread_([this](std::stop_token stop) { run(std::move(stop)); }) {}

void CanReader::run(std::stop_token stop) {
  struct Stamped {
    protocol::CanFrame frame;
    std::int64_t t_us;
  };
  // Up to one batch a lock: at 1 kHz per lever a 50 ms poll finds about a hundred frames.
  std::array<Stamped, 512> batch;
  bool link_up = true;
  while (!stop.stop_requested()) {
    std::size_t n = 0;
    if (link_up) {
      pollfd pfd{can_.fd(), POLLIN, 0};
      if (poll(&pfd, 1, 50) > 0) {
        while (n < batch.size()) {
          std::int64_t t_us = 0;
          const auto status = can_.read(batch[n].frame, t_us);
          if (status == board::IoStatus::ok) {
            batch[n++].t_us = t_us != 0 ? t_us : realtime_us();
          } else if (status == board::IoStatus::skipped) {
            continue;
          } else {
            if (status == board::IoStatus::interface_down || status == board::IoStatus::interface_gone) link_up = false;
            break;
          }
        }
      }
    } else {
      // Down or gone: look again every 0.2 s, reopening a socket whose interface was made anew.
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      link_up = can_.recover() == board::LinkState::up;
    }
    const std::lock_guard lock(live_.mutex);
    for (std::size_t i = 0; i < n; ++i) live_.monitor.on_frame(batch[i].frame, batch[i].t_us);
    live_.reader.link_up = link_up;
    live_.reader.kernel_drops = can_.kernel_drops();
  }
}

}  // namespace lever::view
