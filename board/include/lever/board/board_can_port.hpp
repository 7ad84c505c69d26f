#pragma once
// The lever board's CAN port: the core's CanPort on a SocketCAN interface. The kernel filters the lever pair's
// own frames, so foreign traffic never reaches the loop; the controller's error frames are read here and kept
// as the bus state the runner acts on, never handed to the core; a full transmit queue drops the frame and
// counts it; an interface that goes down, or away and back, is followed without blocking the loop. After
// open(), receive() and send() never block and never allocate.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "lever/board/board_can_port_config.hpp"
#include "lever/board/can_bus_monitor.hpp"
#include "lever/board/result.hpp"
#include "lever/board/socketcan.hpp"
#include "lever/fw/hal.hpp"
#include "lever/protocol/messages.hpp"

namespace lever::board {

// How many identifiers of a pair a lever hears: the message set's rows it hears, per sender where the row is.
constexpr std::size_t lever_heard_id_count() noexcept {
  std::size_t n = 0;
  for (const auto& m : protocol::kMessageSet)
    if (m.lever_hears) n += m.per_sender ? 2 : 1;
  return n;
}

// The kernel filters of a lever pair: every identifier of the pair the message set says a lever hears
// (protocol::MessageSpec::lever_hears), as classic 11-bit data frames (extended and remote frames with the same low
// bits do not pass).
std::array<CanFilter, lever_heard_id_count()> lever_pair_filters(std::uint8_t pair) noexcept;

struct BoardCanStats {
  std::uint64_t rx_frames = 0;        // data frames handed to the core
  std::uint64_t rx_skipped = 0;       // frames read that were not classic data frames (the filters pass none)
  std::uint64_t rx_errors = 0;        // reads that failed for another reason than an empty queue or the link
  std::uint64_t rx_kernel_drops = 0;  // frames the kernel dropped, our receive queue full (SO_RXQ_OVFL)
  std::uint64_t tx_frames = 0;        // frames the kernel took
  std::uint64_t tx_dropped = 0;       // the transmit queue was full (ENOBUFS, EAGAIN): dropped, never waited for
  std::uint64_t tx_link_down = 0;     // not sent: the interface was down or gone
  std::uint64_t tx_errors = 0;        // sends that failed for another reason
  std::uint64_t link_losses = 0;      // the interface went down or away while the port thought it up
  std::uint64_t reopens = 0;          // new sockets, after the interface came back under a new index
};

class BoardCanPort {
 public:
  // Opens a socket on the interface with the pair's filters and the monitored error classes. The interface
  // must exist; it may be down (link() says so until it is up).
  static Result<BoardCanPort> open(const BoardCanPortConfig& config);

  // Move-only: the socket has one owner. A moved-from port owns no socket; it may only be destroyed or
  // assigned to.
  BoardCanPort(BoardCanPort&&) noexcept = default;
  BoardCanPort& operator=(BoardCanPort&&) noexcept = default;
  BoardCanPort(const BoardCanPort&) = delete;
  BoardCanPort& operator=(const BoardCanPort&) = delete;
  ~BoardCanPort() = default;

  // CanPort: the next data frame of the pair, false when there is none. Error frames met on the way update
  // bus_state() and counts and are consumed (at most kMaxReadsPerReceive reads a call, so an error flood
  // cannot hold the loop). While the link is not up, it first checks the link when the retry time is due.
  bool receive(protocol::CanFrame& frame) noexcept;
  // CanPort: false when the frame was not queued (queue full, link down or gone, another error).
  bool send(const protocol::CanFrame& frame) noexcept;

  LinkState link() const noexcept { return link_; }
  // The core's optional HasBusFault: bus-off, or the link down or gone. Error-passive is not a fault here: on
  // a two-node bus it means the peer stopped acknowledging, which the comms timeout already catches.
  bool bus_fault() const noexcept { return link_ != LinkState::up || monitor_.state() == CanBusState::bus_off; }
  CanBusState bus_state() const noexcept { return monitor_.state(); }
  const CanErrorCounts& bus_counts() const noexcept { return monitor_.counts(); }
  BoardCanStats stats() const noexcept;
  std::string_view interface() const noexcept { return socket_.interface(); }
  int last_errno() const noexcept { return socket_.last_errno(); }

  static constexpr std::size_t kMaxReadsPerReceive = 32;

 private:
  BoardCanPort(SocketCan socket, const BoardCanPortConfig& config) noexcept;
  bool check_link() noexcept;
  void lost(LinkState state) noexcept;
  void regained() noexcept;

  SocketCan socket_;
  CanBusMonitor monitor_;
  BoardCanStats stats_;
  LinkState link_ = LinkState::up;
  std::uint64_t retry_first_ns_ = 0, retry_max_ns_ = 0, retry_ns_ = 0, next_check_ns_ = 0;
};

static_assert(fw::CanPort<BoardCanPort>);
static_assert(fw::HasBusFault<BoardCanPort>);

}  // namespace lever::board
