#include "drivers/can/socketcan.h"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <new>

namespace aprt::can {

const char* bus_state_name(BusState s) {
  switch (s) {
    case BusState::kActive: return "error-active";
    case BusState::kWarning: return "error-warning";
    case BusState::kPassive: return "error-passive";
    case BusState::kBusOff: return "bus-off";
  }
  return "?";
}

Expected<std::unique_ptr<SocketCan>> SocketCan::open(const std::string& interface, bool fd,
                                                     bool receive) {
  if (interface.empty() || interface.size() >= IFNAMSIZ) {
    return Error(Errc::kInvalidArgument, "can: interface name '%s' is empty or too long",
                 interface.c_str());
  }
  std::unique_ptr<SocketCan> s(new (std::nothrow) SocketCan());
  if (!s) return Error(Errc::kOutOfMemory, "can: out of memory");
  std::snprintf(s->interface_, sizeof s->interface_, "%s", interface.c_str());
  s->want_fd_ = fd;
  s->receive_ = receive;
  if (Status st = s->bind_socket(); !st) return st.error();
  return s;
}

std::unique_ptr<SocketCan> SocketCan::unbound(const std::string& interface, bool fd, bool receive) {
  std::unique_ptr<SocketCan> s(new (std::nothrow) SocketCan());
  if (!s) return s;
  std::snprintf(s->interface_, sizeof s->interface_, "%s", interface.c_str());
  s->want_fd_ = fd;
  s->receive_ = receive;
  return s;
}

Status SocketCan::bind_socket() noexcept {
  const int fd = socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC | SOCK_NONBLOCK, CAN_RAW);
  if (fd < 0) {
    const int e = errno;
    return Error(Errc::kUnsupported,
                 "can: this kernel has no SocketCAN (socket(PF_CAN) failed: %s; load the can_raw "
                 "module or use a kernel with CONFIG_CAN_RAW)",
                 std::strerror(e));
  }
  ifreq ifr{};
  std::snprintf(ifr.ifr_name, sizeof ifr.ifr_name, "%s", interface_);
  if (ioctl(fd, SIOCGIFINDEX, &ifr) != 0) {
    const int e = errno;
    close(fd);
    return Error(Errc::kNotFound,
                 "can: interface '%s' not found (%s): check `ip link show %s` (for a test rig: ip "
                 "link add dev %s type vcan && ip link set %s up)",
                 interface_, std::strerror(e), interface_, interface_, interface_);
  }
  const int index = ifr.ifr_ifindex;
  if (receive_) {
    // A reader takes classic and FD frames alike (FD frames need an FD interface; no check).
    const int on = 1;
    setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on);
  } else if (want_fd_) {
    if (ioctl(fd, SIOCGIFMTU, &ifr) == 0 && ifr.ifr_mtu != int(CANFD_MTU)) {
      close(fd);
      return Error(Errc::kInvalidArgument,
                   "can: interface '%s' is not CAN FD (mtu %d, expected %d): configure the "
                   "controller with `ip link set %s type can ... fd on` (vcan: mtu 72), or set "
                   "output.can.fd: false",
                   interface_, ifr.ifr_mtu, int(CANFD_MTU), interface_);
    }
    const int on = 1;
    if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) != 0) {
      const int e = errno;
      close(fd);
      return Error(Errc::kUnsupported, "can: CAN FD frames not supported on '%s': %s", interface_,
                   std::strerror(e));
    }
  }
  if (!receive_) {
    // The sender reads only error frames: no data frame is ever queued to it.
    setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, nullptr, 0);
  } else if (Status st = apply_filter(fd); !st) {
    close(fd);
    return st;
  }
  const can_err_mask_t mask =
      CAN_ERR_TX_TIMEOUT | CAN_ERR_LOSTARB | CAN_ERR_CRTL | CAN_ERR_BUSOFF | CAN_ERR_RESTARTED;
  setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &mask, sizeof mask);
  if (receive_) {
    const int on = 1;
    setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = index;
  if (bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    const int e = errno;
    close(fd);
    return Error(Errc::kIo, "can: cannot bind to '%s': %s", interface_, std::strerror(e));
  }
  if (fd_ >= 0) close(fd_);
  fd_ = fd;
  state_ = BusState::kActive;
  return ok();
}

Status SocketCan::apply_filter(int fd) const noexcept {
  if (filter_count_ == 0) return ok();
  can_filter f[kMaxFilterIds];
  for (int i = 0; i < filter_count_; ++i) {
    const uint32_t id = filter_ids_[i];
    const bool extended = id > CAN_SFF_MASK;
    // The frame format is part of the match: 0x123 standard is not 0x123 extended.
    f[i].can_id = extended ? (id | CAN_EFF_FLAG) : id;
    f[i].can_mask = (extended ? CAN_EFF_MASK : CAN_SFF_MASK) | CAN_EFF_FLAG | CAN_RTR_FLAG;
  }
  if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, f, socklen_t(sizeof f[0] * filter_count_)) != 0) {
    const int e = errno;
    return Error(Errc::kIo, "can: cannot set the receive filter on '%s': %s", interface_,
                 std::strerror(e));
  }
  return ok();
}

Status SocketCan::set_filter(const uint32_t* ids, int n) noexcept {
  if (n < 1 || n > kMaxFilterIds) {
    return Error(Errc::kInvalidArgument, "can: %d receive ids (1 to %d)", n, kMaxFilterIds);
  }
  for (int i = 0; i < n; ++i) filter_ids_[i] = ids[i];
  filter_count_ = n;
  return fd_ < 0 ? ok() : apply_filter(fd_);  // else applied when bound
}

SocketCan::~SocketCan() {
  if (fd_ >= 0) close(fd_);
}

bool SocketCan::reopen() noexcept {
  return bool(bind_socket());
}

WriteResult SocketCan::write(const Frame& f) noexcept {
  if (fd_ < 0) {
    last_errno_ = ENODEV;
    return WriteResult::kError;
  }
  ssize_t n;
  if (f.fd) {
    canfd_frame cf{};
    cf.can_id = f.id > CAN_SFF_MASK ? (f.id | CAN_EFF_FLAG) : f.id;
    cf.len = f.len;
    cf.flags = CANFD_BRS;
    std::memcpy(cf.data, f.data, f.len);
    n = send(fd_, &cf, sizeof cf, MSG_DONTWAIT);
  } else {
    can_frame cf{};
    cf.can_id = f.id > CAN_SFF_MASK ? (f.id | CAN_EFF_FLAG) : f.id;
    cf.can_dlc = f.len;
    std::memcpy(cf.data, f.data, f.len > 8 ? 8 : f.len);
    n = send(fd_, &cf, sizeof cf, MSG_DONTWAIT);
  }
  if (n >= 0) return WriteResult::kSent;
  last_errno_ = errno;
  if (last_errno_ == ENOBUFS || last_errno_ == EAGAIN) return WriteResult::kQueueFull;
  if (last_errno_ == ENETDOWN) return WriteResult::kDown;
  return WriteResult::kError;
}

void SocketCan::note_error_frame(const uint8_t* data, uint32_t id) noexcept {
  if (id & CAN_ERR_TX_TIMEOUT) ++tx_timeouts;
  if (id & CAN_ERR_LOSTARB) ++lost_arbitration;
  if (id & CAN_ERR_CRTL) {
    const uint8_t c = data[1];
    if (c & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) {
      ++passive_events;
      if (state_ != BusState::kBusOff) state_ = BusState::kPassive;
    } else if (c & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) {
      ++warning_events;
      if (state_ == BusState::kActive) state_ = BusState::kWarning;
    }
    if (c & CAN_ERR_CRTL_ACTIVE) state_ = BusState::kActive;
  }
  if (id & CAN_ERR_BUSOFF) {
    ++bus_off_events;
    state_ = BusState::kBusOff;
  }
  if (id & CAN_ERR_RESTARTED) {
    ++restarted_events;
    state_ = BusState::kActive;
  }
}

BusState SocketCan::poll_bus() noexcept {
  if (receive_ || fd_ < 0) return state_;  // a reader sees error frames through read()
  for (int i = 0; i < 64; ++i) {
    canfd_frame cf{};
    const ssize_t n = recv(fd_, &cf, sizeof cf, MSG_DONTWAIT);
    if (n <= 0) break;
    if (cf.can_id & CAN_ERR_FLAG) note_error_frame(cf.data, cf.can_id & CAN_ERR_MASK);
  }
  return state_;
}

int SocketCan::read(Frame* f, int timeout_ms, int64_t* timestamp_ns) noexcept {
  pollfd p{fd_, POLLIN, 0};
  const int r = poll(&p, 1, timeout_ms);
  if (r == 0) return 0;
  if (r < 0) {
    last_errno_ = errno;
    return last_errno_ == EINTR ? 0 : -1;
  }
  canfd_frame cf{};
  iovec iov{&cf, sizeof cf};
  alignas(cmsghdr) char control[64];
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  const ssize_t n = recvmsg(fd_, &msg, MSG_DONTWAIT);
  if (n < 0) {
    last_errno_ = errno;
    return last_errno_ == EAGAIN ? 0 : -1;
  }
  *f = Frame{};
  f->fd = size_t(n) == CANFD_MTU;
  f->len = f->fd ? cf.len : (cf.len > 8 ? 8 : cf.len);
  std::memcpy(f->data, cf.data, f->len);
  if (cf.can_id & CAN_ERR_FLAG) {
    note_error_frame(cf.data, cf.can_id & CAN_ERR_MASK);
    f->id = (cf.can_id & CAN_ERR_MASK) | kErrorFrameFlag;
  } else {
    f->id = cf.can_id & ((cf.can_id & CAN_EFF_FLAG) ? CAN_EFF_MASK : CAN_SFF_MASK);
  }
  if (timestamp_ns) {
    *timestamp_ns = 0;
    for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_TIMESTAMPNS) {
        timespec ts;
        std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
        *timestamp_ns = int64_t(ts.tv_sec) * 1000000000 + ts.tv_nsec;
      }
    }
  }
  return 1;
}

}  // namespace aprt::can
