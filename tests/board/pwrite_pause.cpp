#include "pwrite_pause.hpp"

#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cstring>
#include <thread>

namespace lever::test {
namespace {

std::atomic<bool> armed{false};
std::atomic<bool> paused{false};
std::atomic<bool> resumed{false};
void (*armed_meanwhile)() = nullptr;
char armed_text[16];
std::size_t armed_length = 0;
std::chrono::milliseconds armed_pause{0};

}  // namespace

void pause_next_pwrite_of(std::string_view text, std::chrono::milliseconds pause, void (*meanwhile)()) {
  armed_length = text.size() < sizeof armed_text ? text.size() : sizeof armed_text;
  std::memcpy(armed_text, text.data(), armed_length);
  armed_pause = pause;
  armed_meanwhile = meanwhile;
  paused.store(false);
  resumed.store(false);
  armed.store(true);
}

bool pwrite_paused() { return paused.load(); }
bool pwrite_resumed() { return resumed.load(); }

}  // namespace lever::test

extern "C" ssize_t pwrite(int fd, const void* buffer, size_t count, off_t offset) {
  using namespace lever::test;
  if (armed.load() && count == armed_length && std::memcmp(buffer, armed_text, count) == 0 && armed.exchange(false)) {
    paused.store(true);
    std::this_thread::sleep_for(armed_pause);
    if (armed_meanwhile != nullptr) armed_meanwhile();
    const auto written = ::syscall(SYS_pwrite64, fd, buffer, count, offset);
    resumed.store(true);
    return written;
  }
  return ::syscall(SYS_pwrite64, fd, buffer, count, offset);
}
