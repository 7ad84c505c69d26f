#include "lever/linux/socketcan.hpp"

#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>

#include <cerrno>
#include <cstring>

namespace lever::linux_io {

bool SocketCan::open(const std::string& interface) {
  interface_ = interface;
  auto fail = [this](const char* what) {
    errno_ = errno;
    error_ = interface_ + ": " + what + ": " + std::strerror(errno_);
    fd_.reset();
    return false;
  };
  if (interface.empty() || interface.size() >= IFNAMSIZ) {
    errno = EINVAL;
    return fail("bad interface name");
  }
  fd_.reset(::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW));
  if (!fd_) return fail("socket(PF_CAN)");
  ifreq ifr{};
  std::memcpy(ifr.ifr_name, interface.c_str(), interface.size() + 1);
  if (::ioctl(fd_.get(), SIOCGIFINDEX, &ifr) < 0) return fail("no such CAN interface");
  const int on = 1;
  // Kernel receive timestamps make the recorded log and the latency figures independent of our scheduling.
  ::setsockopt(fd_.get(), SOL_SOCKET, SO_TIMESTAMP, &on, sizeof on);
  // The kernel's count of frames dropped for a full receive queue rides on every read: losses become visible.
  ::setsockopt(fd_.get(), SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on);
  kernel_drops_ = 0;
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifr.ifr_ifindex;
  if (::bind(fd_.get(), reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0) return fail("bind");
  error_.clear();
  return true;
}

IoStatus SocketCan::classify(int err) {
  errno_ = err;
  switch (err) {
    case EAGAIN:
    case ENOBUFS:  // the interface's tx queue is full
      return IoStatus::would_block;
    case ENETDOWN:
    case ENXIO:
    case ENODEV:
      return IoStatus::interface_down;
    default:
      error_ = interface_ + ": " + std::strerror(err);
      return IoStatus::error;
  }
}

IoStatus SocketCan::read(protocol::CanFrame& frame, std::int64_t& timestamp_us) {
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
  // Classic frames only; CAN FD or error frames are not part of the lever protocol.
  if (static_cast<std::size_t>(n) != sizeof raw || (raw.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG)) ||
      raw.can_dlc > 8) {
    return IoStatus::skipped;
  }
  frame.id = raw.can_id & CAN_SFF_MASK;
  frame.dlc = raw.can_dlc;
  std::memcpy(frame.data.data(), raw.data, 8);
  timestamp_us = 0;
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_TIMESTAMP) {
      timeval tv;
      std::memcpy(&tv, CMSG_DATA(c), sizeof tv);
      timestamp_us = static_cast<std::int64_t>(tv.tv_sec) * 1'000'000 + tv.tv_usec;
    } else if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
      std::memcpy(&kernel_drops_, CMSG_DATA(c), sizeof kernel_drops_);
    }
  }
  return IoStatus::ok;
}

IoStatus SocketCan::write(const protocol::CanFrame& frame) {
  can_frame raw{};
  raw.can_id = frame.id & CAN_SFF_MASK;
  raw.can_dlc = frame.dlc > 8 ? 8 : frame.dlc;
  std::memcpy(raw.data, frame.data.data(), 8);
  const ssize_t n = ::write(fd_.get(), &raw, sizeof raw);
  if (n < 0) return classify(errno);
  return IoStatus::ok;
}

}  // namespace lever::linux_io
