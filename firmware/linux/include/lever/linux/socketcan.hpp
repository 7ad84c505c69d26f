#pragma once
// A raw SocketCAN socket on one interface, non-blocking, for classic CAN frames. Shared by lever-bridge and
// the board runner. No exceptions: every call says how it went, with errno kept for the message.
#include <cstdint>
#include <string>

#include "lever/linux/unique_fd.hpp"
#include "lever/protocol/can_frame.hpp"

namespace lever::linux_io {

enum class IoStatus : std::uint8_t {
  ok,
  would_block,     // nothing to read, or the send queue is full (ENOBUFS): try later
  interface_down,  // ENETDOWN / ENXIO / ENODEV: the interface went away or down; reopen later
  error,           // anything else; last_errno() tells
  skipped,         // a frame that is not a classic 11-bit data frame (extended, RTR, error): not ours, dropped
};

class SocketCan {
 public:
  SocketCan() = default;

  // Opens and binds; false with a message in error_text() on failure.
  bool open(const std::string& interface);
  void close() { fd_.reset(); }
  bool is_open() const { return static_cast<bool>(fd_); }
  int fd() const { return fd_.get(); }
  const std::string& interface() const { return interface_; }

  // One frame; timestamp_us is the kernel's receive time (SO_TIMESTAMP), 0 if unavailable.
  IoStatus read(protocol::CanFrame& frame, std::int64_t& timestamp_us);
  IoStatus write(const protocol::CanFrame& frame);

  // Frames the kernel dropped because this socket's receive queue was full (SO_RXQ_OVFL), since open().
  std::uint32_t kernel_drops() const { return kernel_drops_; }
  int last_errno() const { return errno_; }
  const std::string& error_text() const { return error_; }

 private:
  IoStatus classify(int err);
  UniqueFd fd_;
  std::string interface_;
  int errno_ = 0;
  std::uint32_t kernel_drops_ = 0;
  std::string error_;
};

}  // namespace lever::linux_io
