#include "lever/board/board_can_port.hpp"

#include <linux/can.h>

#include <algorithm>
#include <cerrno>
#include <utility>

#include "lever/board/config_error.hpp"
#include "lever/board/monotonic_clock.hpp"
#include "lever/protocol/messages.hpp"

namespace lever::board {

namespace {}  // namespace

std::array<CanFilter, lever_heard_id_count()> lever_pair_filters(std::uint8_t pair) noexcept {
  // The flags in the mask must match the id's (zero): an extended or remote frame with the same 11 low bits
  // is someone else's. The lever's own frames do not come back: the socket does not receive its own.
  constexpr std::uint32_t mask = CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG;
  using protocol::Role;
  std::array<CanFilter, lever_heard_id_count()> filters{};
  std::size_t n = 0;
  for (const auto& m : protocol::kMessageSet) {
    if (!m.lever_hears) continue;
    filters[n++] = {protocol::message_id(m.kind, pair, m.per_sender ? Role::hsi : m.sender), mask};
    if (m.per_sender) filters[n++] = {protocol::message_id(m.kind, pair, Role::top), mask};
  }
  return filters;
}

Result<BoardCanPort> BoardCanPort::open(const BoardCanPortConfig& config) {
  if (const auto problems = config.validate(); !problems.empty()) return config_error("CAN port config", problems);
  const auto filters = lever_pair_filters(config.pair);
  SocketCanConfig socket_config;
  socket_config.interface = config.interface;
  socket_config.filters.assign(filters.begin(), filters.end());
  socket_config.error_classes = kMonitoredErrorClasses;
  socket_config.timestamps = false;  // the core takes frames at its tick; a kernel time would go unused
  auto socket = SocketCan::open(socket_config);
  if (!socket) return socket.error();
  return BoardCanPort(std::move(socket).value(), config);
}

BoardCanPort::BoardCanPort(SocketCan socket, const BoardCanPortConfig& config) noexcept
    : socket_(std::move(socket)),
      retry_first_ns_(std::uint64_t{config.link_retry_ms} * 1'000'000u),
      retry_max_ns_(std::uint64_t{config.link_retry_max_ms} * 1'000'000u),
      retry_ns_(retry_first_ns_) {
  // An interface may be down when the board starts; it is then followed like one that went down later.
  const LinkState now = socket_.link_state();
  if (now != LinkState::up) {
    link_ = now;
    next_check_ns_ = static_cast<std::uint64_t>(monotonic_ns()) + retry_ns_;
  }
}

BoardCanStats BoardCanPort::stats() const noexcept {
  BoardCanStats s = stats_;
  s.rx_kernel_drops = socket_.kernel_drops();
  s.reopens = socket_.reopens();
  return s;
}

void BoardCanPort::lost(LinkState state) noexcept {
  if (link_ == LinkState::up) {
    ++stats_.link_losses;
    retry_ns_ = retry_first_ns_;
    next_check_ns_ = static_cast<std::uint64_t>(monotonic_ns()) + retry_ns_;
  }
  // Down may turn into gone (removed while down); gone stays gone until a new socket is bound.
  if (link_ != LinkState::gone) link_ = state;
}

void BoardCanPort::regained() noexcept {
  link_ = LinkState::up;
  retry_ns_ = retry_first_ns_;
  // Drivers start their controller error-active when the interface is brought up, and no error frame says so.
  monitor_.on_controller_started();
}

bool BoardCanPort::check_link() noexcept {
  const std::uint64_t now = static_cast<std::uint64_t>(monotonic_ns());
  if (now < next_check_ns_) return false;
  const LinkState state = socket_.recover();
  if (state == LinkState::up) {
    regained();
    return true;
  }
  link_ = state;
  next_check_ns_ = now + retry_ns_;
  retry_ns_ = std::min(retry_ns_ * 2, retry_max_ns_);
  return false;
}

bool BoardCanPort::receive(protocol::CanFrame& frame) noexcept {
  if (link_ != LinkState::up && !check_link()) return false;
  for (std::size_t i = 0; i < kMaxReadsPerReceive; ++i) {
    std::int64_t timestamp_us = 0;
    CanErrorFrame error;
    switch (socket_.read(frame, timestamp_us, error)) {
      case IoStatus::ok:
        ++stats_.rx_frames;
        return true;
      case IoStatus::error_frame:
        monitor_.on_error_frame(error);
        continue;
      case IoStatus::skipped:
        ++stats_.rx_skipped;
        continue;
      case IoStatus::would_block:
        return false;
      case IoStatus::interface_down:
        lost(LinkState::down);
        return false;
      case IoStatus::interface_gone:
        lost(LinkState::gone);
        return false;
      case IoStatus::error:
        ++stats_.rx_errors;
        return false;
    }
  }
  return false;
}

bool BoardCanPort::send(const protocol::CanFrame& frame) noexcept {
  // An unbound socket can send nowhere; receive() reopens it when the interface is back.
  if (link_ == LinkState::gone) {
    ++stats_.tx_link_down;
    return false;
  }
  switch (socket_.write(frame)) {
    case IoStatus::ok:
      ++stats_.tx_frames;
      // The kernel refuses frames on a down interface, so a frame taken proves it up again.
      if (link_ != LinkState::up) regained();
      return true;
    case IoStatus::would_block:
      ++stats_.tx_dropped;
      return false;
    case IoStatus::interface_down:
      ++stats_.tx_link_down;
      lost(LinkState::down);
      return false;
    case IoStatus::interface_gone:
      ++stats_.tx_link_down;
      lost(LinkState::gone);
      return false;
    default:
      ++stats_.tx_errors;
      return false;
  }
}

}  // namespace lever::board
