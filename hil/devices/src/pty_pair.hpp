#pragma once
// A pseudo-terminal pair in raw mode, the serial line between a simulated RTU device (on the master end) and
// the program under test (which opens the slave end's path as its serial port).
#include <string>

#include "lever/board/result.hpp"
#include "lever/board/unique_fd.hpp"

namespace lever::hil::devices {

class PtyPair {
 public:
  static board::Result<PtyPair> open();

  int master() const noexcept { return master_.get(); }
  const std::string& slave_path() const noexcept { return slave_path_; }  // "/dev/pts/7"

 private:
  PtyPair() = default;
  board::UniqueFd master_;
  // Held open for the pair's life: when the last holder of the slave closes it, reads on the master fail with
  // EIO (a hangup) until someone opens it again, and a client that closes and reopens its serial port (a
  // reconnect, a restarted process) would make the device side see that.
  board::UniqueFd slave_held_open_;
  std::string slave_path_;
};

}  // namespace lever::hil::devices
