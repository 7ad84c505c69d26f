#pragma once
// A raw SocketCAN socket on one interface, non-blocking unless asked, for classic CAN frames: kernel receive
// filters, error frames on request, and the interface's state. Shared by lever-bridge and the board's CAN port
// (board_can_port.hpp). No exceptions; after open(), no call allocates.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "lever/board/result.hpp"
#include "lever/board/unique_fd.hpp"
#include "lever/protocol/can_frame.hpp"

namespace lever::board {

enum class IoStatus : std::uint8_t {
  ok,
  would_block,     // nothing to read, or no room to send (EAGAIN, ENOBUFS: the interface's queue is full)
  interface_down,  // ENETDOWN: the interface is down; the socket stays bound and works again once it is up
  interface_gone,  // ENODEV / ENXIO: the interface was removed, which unbinds the socket: reopen() it
  error,           // anything else; last_errno() tells
  skipped,         // a frame that is not a classic 11-bit data frame (extended, RTR, CAN FD): dropped
  error_frame,     // an error frame (only on a socket opened with error_classes)
};

// A kernel receive filter: a frame passes when (its id & mask) == (id & mask). The flag bits of linux/can.h
// (CAN_EFF_FLAG, CAN_RTR_FLAG) take part when the mask has them.
struct CanFilter {
  std::uint32_t id = 0;
  std::uint32_t mask = 0;
};

// An error frame as the kernel sends it (linux/can/error.h): the CAN_ERR_* classes from its id, and its data.
struct CanErrorFrame {
  std::uint32_t classes = 0;
  std::array<std::uint8_t, 8> data{};
};

// What the kernel says of the interface, looked up by name.
enum class LinkState : std::uint8_t {
  up,
  down,  // administratively down (ip link set ... down)
  gone,  // no interface has the name, or the socket lost its binding (the interface was removed)
};

struct SocketCanConfig {
  std::string interface;
  std::vector<CanFilter> filters;   // none: every frame
  std::uint32_t error_classes = 0;  // CAN_ERR_* classes to receive as error frames (CAN_RAW_ERR_FILTER); 0: none
  bool timestamps = true;           // the kernel's receive time on every frame (SO_TIMESTAMP)
  // A socket whose reads block (for a thread that waits in recvmmsg on it); write() never blocks either way
  // (MSG_DONTWAIT). Kept across reopen().
  bool blocking = false;
};

class SocketCan {
 public:
  static constexpr std::size_t kMaxFilters = 16;
  static constexpr std::size_t kMaxInterfaceName = 15;  // IFNAMSIZ less its terminator

  // Creates, configures and binds the socket; fails naming the interface, the step and the reason.
  static Result<SocketCan> open(const SocketCanConfig& config);

  // Move-only: the socket has one owner. A moved-from SocketCan has no socket; it may only be destroyed or
  // assigned to.
  SocketCan(SocketCan&&) noexcept = default;
  SocketCan& operator=(SocketCan&&) noexcept = default;
  SocketCan(const SocketCan&) = delete;
  SocketCan& operator=(const SocketCan&) = delete;
  ~SocketCan() = default;

  // One frame; timestamp_us is the kernel's receive time (0 without timestamps). An error frame fills
  // `error` and returns IoStatus::error_frame. The short form is for sockets opened without error classes.
  IoStatus read(protocol::CanFrame& frame, std::int64_t& timestamp_us, CanErrorFrame& error) noexcept;
  IoStatus read(protocol::CanFrame& frame, std::int64_t& timestamp_us) noexcept;
  IoStatus write(const protocol::CanFrame& frame) noexcept;

  // Asks the kernel about the interface of our name now (two ioctls; no allocation). `gone` also when a new
  // interface took the name after ours was removed: the socket is bound to the old one.
  LinkState link_state() const noexcept;
  // A fresh socket with the same options on the interface that has our name now, replacing this one on
  // success under the same descriptor number (dup3), so that a thread blocked on fd() or holding it goes on
  // with a valid descriptor; on failure the old socket stays and last_errno() says why. No allocation.
  bool reopen() noexcept;
  // link_state(), after a reopen() when the interface was gone and one of our name is there again: what a
  // user whose interface went down or away calls now and then until it says up.
  LinkState recover() noexcept;
  std::uint64_t reopens() const noexcept { return reopens_; }

  int fd() const noexcept { return fd_.get(); }
  std::string_view interface() const noexcept { return {name_.data()}; }
  // Frames the kernel dropped because the receive queue was full (SO_RXQ_OVFL), summed over reopens.
  std::uint64_t kernel_drops() const noexcept { return drops_before_ + drops_; }
  int last_errno() const noexcept { return errno_; }

 private:
  SocketCan() = default;
  IoStatus classify(int err) noexcept;
  // Every step of open() and reopen(); on failure returns the step's name and leaves errno set.
  const char* open_socket(UniqueFd& fd, int& ifindex) const noexcept;

  UniqueFd fd_;
  std::array<char, kMaxInterfaceName + 1> name_{};
  std::array<CanFilter, kMaxFilters> filters_{};
  std::size_t filter_count_ = 0;
  std::uint32_t error_classes_ = 0;
  bool timestamps_ = true;
  bool blocking_ = false;
  int ifindex_ = 0;
  bool unbound_ = false;  // the kernel reported the interface removed
  int errno_ = 0;
  std::uint32_t drops_ = 0;  // this socket's count
  std::uint64_t drops_before_ = 0;
  std::uint64_t reopens_ = 0;
};

}  // namespace lever::board
