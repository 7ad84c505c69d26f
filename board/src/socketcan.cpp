#include "lever/board/socketcan.hpp"

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

#include "lever/board/interface_name.hpp"

namespace lever::board {

static_assert(SocketCan::kMaxInterfaceName + 1 == IFNAMSIZ);
static_assert(sizeof(CanFilter) == sizeof(can_filter) && sizeof(CanFilter::id) == sizeof(can_filter::can_id));

namespace {

ifreq request_for(const std::array<char, SocketCan::kMaxInterfaceName + 1>& name) noexcept {
  ifreq ifr{};
  std::memcpy(ifr.ifr_name, name.data(), name.size());
  return ifr;
}

}  // namespace

Result<SocketCan> SocketCan::open(const SocketCanConfig& config) {
  const std::string& name = config.interface;
  if (const auto problem = interface_name_problem(name))
    return Error{"CAN interface \"" + name + "\": not a valid interface name: " + *problem, EINVAL};
  if (config.filters.size() > kMaxFilters) {
    return Error{name + ": " + std::to_string(config.filters.size()) + " receive filters, at most " +
                     std::to_string(kMaxFilters),
                 EINVAL};
  }
  SocketCan can;
  std::memcpy(can.name_.data(), name.data(), name.size());
  for (const auto& f : config.filters) can.filters_[can.filter_count_++] = f;
  can.error_classes_ = config.error_classes & CAN_ERR_MASK;
  can.timestamps_ = config.timestamps;
  can.blocking_ = config.blocking;
  if (const char* step = can.open_socket(can.fd_, can.ifindex_)) {
    const int err = errno;
    return Error{name + ": " + step + ": " + std::strerror(err), err};
  }
  return can;
}

const char* SocketCan::open_socket(UniqueFd& fd, int& ifindex) const noexcept {
  fd.reset(::socket(PF_CAN, SOCK_RAW | (blocking_ ? 0 : SOCK_NONBLOCK) | SOCK_CLOEXEC, CAN_RAW));
  if (!fd) return "socket(PF_CAN)";
  ifreq ifr = request_for(name_);
  if (::ioctl(fd.get(), SIOCGIFINDEX, &ifr) < 0) return "no such CAN interface";
  ifindex = ifr.ifr_ifindex;
  // Before bind: frames that arrive between bind and the filter would pass unfiltered.
  // An empty list (count 0) leaves the kernel's default, which passes every frame.
  if (filter_count_ > 0 && ::setsockopt(fd.get(), SOL_CAN_RAW, CAN_RAW_FILTER, filters_.data(),
                                        static_cast<socklen_t>(filter_count_ * sizeof(can_filter))) < 0) {
    return "CAN_RAW_FILTER";
  }
  if (error_classes_ != 0) {
    const can_err_mask_t mask = error_classes_;
    if (::setsockopt(fd.get(), SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &mask, sizeof mask) < 0) return "CAN_RAW_ERR_FILTER";
  }
  const int on = 1;
  // Kernel receive timestamps make the recorded log and the latency figures independent of our scheduling.
  if (timestamps_ && ::setsockopt(fd.get(), SOL_SOCKET, SO_TIMESTAMP, &on, sizeof on) < 0) return "SO_TIMESTAMP";
  // The kernel's count of frames dropped for a full receive queue rides on every read: losses become visible.
  if (::setsockopt(fd.get(), SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on) < 0) return "SO_RXQ_OVFL";
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifindex;
  if (::bind(fd.get(), reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0) return "bind";
  return nullptr;
}

bool SocketCan::reopen() noexcept {
  UniqueFd fd;
  int ifindex = 0;
  if (open_socket(fd, ifindex) != nullptr) {
    errno_ = errno;
    return false;
  }
  if (fd_) {
    // The new socket under the old number, the old one closed in the same step: a reader blocked on the number
    // keeps the old socket until its call returns, then reads the new one.
    if (::dup3(fd.get(), fd_.get(), O_CLOEXEC) < 0) {
      errno_ = errno;
      return false;
    }
  } else {
    fd_ = std::move(fd);
  }
  ifindex_ = ifindex;
  unbound_ = false;
  drops_before_ += drops_;
  drops_ = 0;
  ++reopens_;
  return true;
}

LinkState SocketCan::recover() noexcept {
  const LinkState state = link_state();
  if (state != LinkState::gone || !reopen()) return state;
  return link_state();
}

LinkState SocketCan::link_state() const noexcept {
  if (unbound_ || !fd_) return LinkState::gone;
  ifreq ifr = request_for(name_);
  if (::ioctl(fd_.get(), SIOCGIFINDEX, &ifr) < 0 || ifr.ifr_ifindex != ifindex_) return LinkState::gone;
  if (::ioctl(fd_.get(), SIOCGIFFLAGS, &ifr) < 0) return LinkState::gone;
  return (ifr.ifr_flags & IFF_UP) ? LinkState::up : LinkState::down;
}

IoStatus SocketCan::classify(int err) noexcept {
  errno_ = err;
  switch (err) {
    case EAGAIN:
    case ENOBUFS:  // the interface's tx queue is full
      return IoStatus::would_block;
    case ENETDOWN:
      return IoStatus::interface_down;
    case ENXIO:   // send: the bound ifindex no longer exists
    case ENODEV:  // receive: the kernel unbound us when the interface was unregistered
      unbound_ = true;
      return IoStatus::interface_gone;
    default:
      return IoStatus::error;
  }
}

IoStatus SocketCan::read(protocol::CanFrame& frame, std::int64_t& timestamp_us, CanErrorFrame& error) noexcept {
  can_frame raw{};
  iovec iov{&raw, sizeof raw};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timeval)) + CMSG_SPACE(sizeof(std::uint32_t))];
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  const ssize_t n = ::recvmsg(fd_.get(), &msg, 0);
  if (n < 0) return classify(errno);
  timestamp_us = 0;
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_TIMESTAMP) {
      timeval tv;
      std::memcpy(&tv, CMSG_DATA(c), sizeof tv);
      timestamp_us = static_cast<std::int64_t>(tv.tv_sec) * 1'000'000 + tv.tv_usec;
    } else if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
      std::memcpy(&drops_, CMSG_DATA(c), sizeof drops_);
    }
  }
  if (static_cast<std::size_t>(n) != sizeof raw || raw.can_dlc > 8) return IoStatus::skipped;  // CAN FD
  if (raw.can_id & CAN_ERR_FLAG) {
    error.classes = raw.can_id & CAN_ERR_MASK;
    std::memcpy(error.data.data(), raw.data, 8);
    return IoStatus::error_frame;
  }
  // Classic 11-bit data frames only: extended or remote frames are not part of the lever protocol.
  if (raw.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG)) return IoStatus::skipped;
  frame.id = raw.can_id & CAN_SFF_MASK;
  frame.dlc = raw.can_dlc;
  std::memcpy(frame.data.data(), raw.data, 8);
  return IoStatus::ok;
}

IoStatus SocketCan::read(protocol::CanFrame& frame, std::int64_t& timestamp_us) noexcept {
  CanErrorFrame error;
  const IoStatus status = read(frame, timestamp_us, error);
  return status == IoStatus::error_frame ? IoStatus::skipped : status;
}

IoStatus SocketCan::write(const protocol::CanFrame& frame) noexcept {
  can_frame raw{};
  raw.can_id = frame.id & CAN_SFF_MASK;
  raw.can_dlc = frame.dlc > 8 ? 8 : frame.dlc;
  std::memcpy(raw.data, frame.data.data(), 8);
  const ssize_t n = ::send(fd_.get(), &raw, sizeof raw, MSG_DONTWAIT);
  if (n < 0) return classify(errno);
  return IoStatus::ok;
}

}  // namespace lever::board
