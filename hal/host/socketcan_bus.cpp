// SocketCanBus: non-blocking CAN_RAW socket (or SEQPACKET link) with error-frame decoding.
#include "hal/host/socketcan_bus.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>

namespace uwbnav::hal {
namespace {

static_assert(sizeof(struct can_frame) == kCanMtu, "struct can_frame size");
static_assert(sizeof(struct canfd_frame) == kCanFdMtu, "struct canfd_frame size");

bool valid_fd_len(uint8_t len) {
  return len <= 8 || len == 12 || len == 16 || len == 20 || len == 24 || len == 32 || len == 48 || len == 64;
}

std::string errno_text(const char* what, int err) {
  return std::string(what) + ": " + std::strerror(err);
}

Status set_nonblocking(int fd) {
  const int fl = ::fcntl(fd, F_GETFL, 0);
  if (fl < 0 || ::fcntl(fd, F_SETFL, fl | O_NONBLOCK) < 0) return Status::kIoError;
  return Status::kOk;
}

}  // namespace

size_t to_wire(const CanFrame& frame, bool fd_enabled, uint8_t (&buf)[kCanFdMtu]) {
  std::memset(buf, 0, sizeof(buf));
  canid_t id = 0;
  if ((frame.flags & CanFrame::kFlagError) != 0) {
    id = (frame.id & CAN_ERR_MASK) | CAN_ERR_FLAG;
  } else if ((frame.flags & CanFrame::kFlagExtended) != 0) {
    id = (frame.id & CAN_EFF_MASK) | CAN_EFF_FLAG;
  } else {
    if (frame.id > CAN_SFF_MASK) return 0;
    id = frame.id;
  }
  if ((frame.flags & CanFrame::kFlagFd) != 0) {
    if (!fd_enabled || !valid_fd_len(frame.len)) return 0;
    struct canfd_frame cf;
    std::memset(&cf, 0, sizeof(cf));
    cf.can_id = id;
    cf.len = frame.len;
    cf.flags = static_cast<uint8_t>((frame.flags & CanFrame::kFlagBrs) != 0 ? CANFD_BRS : 0);
    std::memcpy(cf.data, frame.data, frame.len);
    std::memcpy(buf, &cf, sizeof(cf));
    return kCanFdMtu;
  }
  if (frame.len > CAN_MAX_DLEN) return 0;
  struct can_frame cf;
  std::memset(&cf, 0, sizeof(cf));
  cf.can_id = id;
  cf.len = frame.len;
  std::memcpy(cf.data, frame.data, frame.len);
  std::memcpy(buf, &cf, sizeof(cf));
  return kCanMtu;
}

Status from_wire(const uint8_t* buf, size_t n, CanFrame& out) {
  canid_t id = 0;
  CanFrame f;
  f.t_us = out.t_us;
  if (n == kCanMtu) {
    struct can_frame cf;
    std::memcpy(&cf, buf, sizeof(cf));
    if (cf.len > CAN_MAX_DLEN) return Status::kInvalidArgument;
    id = cf.can_id;
    f.len = cf.len;
    std::memcpy(f.data, cf.data, cf.len);
  } else if (n == kCanFdMtu) {
    struct canfd_frame cf;
    std::memcpy(&cf, buf, sizeof(cf));
    if (cf.len > CANFD_MAX_DLEN) return Status::kInvalidArgument;
    id = cf.can_id;
    f.len = cf.len;
    f.flags |= CanFrame::kFlagFd;
    if ((cf.flags & CANFD_BRS) != 0) f.flags |= CanFrame::kFlagBrs;
    std::memcpy(f.data, cf.data, cf.len);
  } else {
    return Status::kInvalidArgument;
  }
  if ((id & CAN_RTR_FLAG) != 0) return Status::kUnsupported;
  if ((id & CAN_ERR_FLAG) != 0) {
    f.flags |= CanFrame::kFlagError;
    f.id = id & CAN_ERR_MASK;
  } else if ((id & CAN_EFF_FLAG) != 0) {
    f.flags |= CanFrame::kFlagExtended;
    f.id = id & CAN_EFF_MASK;
  } else {
    f.id = id & CAN_SFF_MASK;
  }
  out = f;
  return Status::kOk;
}

CanErrorInfo decode_error_frame(const CanFrame& frame) {
  CanErrorInfo e;
  const uint32_t c = frame.id & CAN_ERR_MASK;
  const uint8_t* d = frame.data;
  e.classes = c;
  e.tx_timeout = (c & CAN_ERR_TX_TIMEOUT) != 0;
  e.lost_arbitration = (c & CAN_ERR_LOSTARB) != 0;
  e.controller = (c & CAN_ERR_CRTL) != 0;
  e.protocol = (c & CAN_ERR_PROT) != 0;
  e.transceiver = (c & CAN_ERR_TRX) != 0;
  e.no_ack = (c & CAN_ERR_ACK) != 0;
  e.bus_off = (c & CAN_ERR_BUSOFF) != 0;
  e.bus_error = (c & CAN_ERR_BUSERROR) != 0;
  e.restarted = (c & CAN_ERR_RESTARTED) != 0;
  e.has_error_counters = (c & CAN_ERR_CNT) != 0;
  if (e.lost_arbitration) e.lost_arbitration_bit = d[0];
  if (e.controller) {
    e.controller_status = d[1];
    e.rx_overflow = (d[1] & CAN_ERR_CRTL_RX_OVERFLOW) != 0;
    e.tx_overflow = (d[1] & CAN_ERR_CRTL_TX_OVERFLOW) != 0;
    e.warning = (d[1] & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) != 0;
    e.passive = (d[1] & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) != 0;
    e.back_to_active = (d[1] & CAN_ERR_CRTL_ACTIVE) != 0;
  }
  if (e.protocol) {
    e.protocol_type = d[2];
    e.protocol_location = d[3];
  }
  if (e.transceiver) e.transceiver_status = d[4];
  if (e.has_error_counters) {
    e.tx_error_count = d[6];
    e.rx_error_count = d[7];
  }
  return e;
}

std::string describe_error(const CanErrorInfo& e) {
  std::string s;
  auto add = [&s](const char* w) {
    if (!s.empty()) s += ' ';
    s += w;
  };
  if (e.tx_timeout) add("tx-timeout");
  if (e.lost_arbitration) add("lost-arbitration");
  if (e.controller) {
    add("controller(");
    if (e.rx_overflow) s += "rx-overflow,";
    if (e.tx_overflow) s += "tx-overflow,";
    if (e.warning) s += "warning,";
    if (e.passive) s += "passive,";
    if (e.back_to_active) s += "active,";
    if (s.back() == ',') s.pop_back();
    s += ')';
  }
  if (e.protocol) add("protocol-violation");
  if (e.transceiver) add("transceiver");
  if (e.no_ack) add("no-ack");
  if (e.bus_off) add("bus-off");
  if (e.bus_error) add("bus-error");
  if (e.restarted) add("restarted");
  if (e.has_error_counters) {
    add(("tec=" + std::to_string(e.tx_error_count) + " rec=" + std::to_string(e.rx_error_count)).c_str());
  }
  if (s.empty()) s = "unspecified";
  return s;
}

SocketCanBus::~SocketCanBus() { close(); }

void SocketCanBus::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  state_ = CanBusState::kDown;
}

Status SocketCanBus::open(const std::string& ifname, const SocketCanOptions& options) {
  close();
  options_ = options;
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    const int err = errno;
    if (err == EAFNOSUPPORT || err == EPROTONOSUPPORT) {
      last_error_ = "this kernel has no SocketCAN (socket(PF_CAN) failed: " + std::string(std::strerror(err)) +
                    "); load can/can_raw or use a link transport";
      return Status::kUnsupported;
    }
    last_error_ = errno_text("socket(PF_CAN, SOCK_RAW, CAN_RAW)", err);
    return Status::kIoError;
  }
  const unsigned ifindex = ::if_nametoindex(ifname.c_str());
  if (ifindex == 0) {
    last_error_ = "no CAN interface named '" + ifname + "'";
    ::close(fd);
    return Status::kNotFound;
  }
  if (options.error_frames) {
    const can_err_mask_t mask = CAN_ERR_MASK;
    if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &mask, sizeof(mask)) != 0) {
      last_error_ = errno_text("setsockopt(CAN_RAW_ERR_FILTER)", errno);
      ::close(fd);
      return Status::kIoError;
    }
  }
  if (options.fd) {
    const int on = 1;
    if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof(on)) != 0) {
      last_error_ = errno_text("setsockopt(CAN_RAW_FD_FRAMES): no CAN FD support", errno);
      ::close(fd);
      return Status::kUnsupported;
    }
  }
  const int on = 1;
  ignore_status(::setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof(on)) == 0 ? Status::kOk : Status::kIoError);
  struct sockaddr_can addr;
  std::memset(&addr, 0, sizeof(addr));
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(ifindex);
  if (::bind(fd, reinterpret_cast<struct sockaddr*>(&addr), sizeof(addr)) != 0) {
    last_error_ = errno_text(("bind(" + ifname + ")").c_str(), errno);
    ::close(fd);
    return Status::kIoError;
  }
  fd_ = fd;
  can_socket_ = true;
  state_ = CanBusState::kErrorActive;
  last_error_.clear();
  return Status::kOk;
}

Status SocketCanBus::adopt_fd(int fd, const SocketCanOptions& options) {
  close();
  if (fd < 0) return Status::kInvalidArgument;
  if (set_nonblocking(fd) != Status::kOk) {
    last_error_ = errno_text("fcntl(O_NONBLOCK)", errno);
    return Status::kIoError;
  }
  options_ = options;
  fd_ = fd;
  can_socket_ = false;
  state_ = CanBusState::kErrorActive;
  last_error_.clear();
  return Status::kOk;
}

uint64_t SocketCanBus::now_us() const {
  if (options_.clock != nullptr) return options_.clock->now_us();
  struct timespec ts;
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1000000U + static_cast<uint64_t>(ts.tv_nsec) / 1000U;
}

Status SocketCanBus::send(const CanFrame& frame) {
  uint8_t buf[kCanFdMtu];
  const size_t n = to_wire(frame, options_.fd, buf);
  if (n == 0) return Status::kInvalidArgument;
  if (fd_ < 0 || state_ == CanBusState::kDown || state_ == CanBusState::kBusOff) {
    ++counters_.tx_dropped;
    return Status::kIoError;
  }
  const ssize_t rc = ::send(fd_, buf, n, MSG_DONTWAIT | MSG_NOSIGNAL);
  if (rc == static_cast<ssize_t>(n)) {
    ++counters_.tx_ok;
    return Status::kOk;
  }
  ++counters_.tx_dropped;
  if (rc < 0) {
    const int err = errno;
    if (err == EAGAIN || err == EWOULDBLOCK || err == ENOBUFS) return Status::kWouldBlock;
    if (err == ENETDOWN || err == ENXIO || err == ENODEV || err == EPIPE || err == ECONNRESET || err == ENOTCONN) {
      state_ = CanBusState::kDown;
    }
    last_error_ = errno_text("send", err);
  } else {
    last_error_ = "short send";
  }
  return Status::kIoError;
}

void SocketCanBus::on_error_frame(const CanFrame& frame) {
  const CanErrorInfo e = decode_error_frame(frame);
  last_error_frame_ = e;
  ++counters_.error_frames;
  if (e.tx_timeout) ++errors_.tx_timeout;
  if (e.lost_arbitration) ++errors_.lost_arbitration;
  if (e.controller) ++errors_.controller;
  if (e.protocol) ++errors_.protocol;
  if (e.transceiver) ++errors_.transceiver;
  if (e.no_ack) ++errors_.no_ack;
  if (e.bus_error) ++errors_.bus_error;
  if (e.warning) ++errors_.warning;
  if (e.passive) ++errors_.passive;
  if (e.rx_overflow) ++counters_.rx_overflow;
  if (e.has_error_counters) {
    errors_.tx_error_count = e.tx_error_count;
    errors_.rx_error_count = e.rx_error_count;
  }
  if (e.restarted) {
    ++errors_.restarted;
    state_ = CanBusState::kErrorActive;
  }
  if (e.back_to_active && state_ != CanBusState::kBusOff) state_ = CanBusState::kErrorActive;
  if (e.passive && state_ == CanBusState::kErrorActive) state_ = CanBusState::kErrorPassive;
  if (e.bus_off) {
    ++counters_.bus_off;
    state_ = CanBusState::kBusOff;
  }
  last_error_ = "error frame: " + describe_error(e);
}

Status SocketCanBus::receive(CanFrame& out) {
  if (fd_ < 0) return Status::kIoError;
  // Error frames are consumed here; bound the work per call.
  for (int i = 0; i < 64; ++i) {
    uint8_t buf[kCanFdMtu];
    struct iovec iov;
    iov.iov_base = buf;
    iov.iov_len = sizeof(buf);
    alignas(struct cmsghdr) uint8_t control[CMSG_SPACE(sizeof(uint32_t))];
    struct msghdr msg;
    std::memset(&msg, 0, sizeof(msg));
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof(control);
    const ssize_t n = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
    if (n < 0) {
      const int err = errno;
      if (err == EAGAIN || err == EWOULDBLOCK) return Status::kEmpty;
      if (err == EINTR) continue;
      last_error_ = errno_text("recvmsg", err);
      if (err == ENETDOWN || err == ENXIO || err == ENODEV || err == ECONNRESET) state_ = CanBusState::kDown;
      return Status::kIoError;
    }
    if (n == 0) {
      last_error_ = "link closed by peer";
      state_ = CanBusState::kDown;
      return Status::kIoError;
    }
    for (struct cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
        uint32_t dropped = 0;
        std::memcpy(&dropped, CMSG_DATA(c), sizeof(dropped));
        counters_.rx_overflow += dropped - rxq_dropped_;
        rxq_dropped_ = dropped;
      }
    }
    CanFrame f;
    if (from_wire(buf, static_cast<size_t>(n), f) != Status::kOk) {
      last_error_ = "unreadable record of " + std::to_string(n) + " bytes";
      continue;
    }
    f.t_us = now_us();
    if ((f.flags & CanFrame::kFlagError) != 0) {
      on_error_frame(f);
      continue;
    }
    ++counters_.rx_ok;
    out = f;
    return Status::kOk;
  }
  return Status::kEmpty;
}

// Fills a Unix socket address for `path` and opens a SOCK_SEQPACKET socket.
static Status seqpacket_socket(const std::string& path, struct sockaddr_un& addr, int& fd, std::string* error) {
  std::memset(&addr, 0, sizeof(addr));
  addr.sun_family = AF_UNIX;
  if (path.size() >= sizeof(addr.sun_path)) {
    if (error != nullptr) *error = "socket path too long: " + path;
    return Status::kInvalidArgument;
  }
  std::memcpy(addr.sun_path, path.c_str(), path.size());
  fd = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    if (error != nullptr) *error = errno_text("socket(AF_UNIX, SOCK_SEQPACKET)", errno);
    return Status::kIoError;
  }
  return Status::kOk;
}

Status can_link_listen(const std::string& path, int& listen_fd, std::string* error) {
  struct sockaddr_un addr;
  int fd = -1;
  const Status s = seqpacket_socket(path, addr, fd, error);
  if (!ok(s)) return s;
  ::unlink(path.c_str());
  if (::bind(fd, reinterpret_cast<struct sockaddr*>(&addr), sizeof(addr)) != 0 || ::listen(fd, 1) != 0) {
    if (error != nullptr) *error = errno_text(("bind/listen " + path).c_str(), errno);
    ::close(fd);
    return Status::kIoError;
  }
  listen_fd = fd;
  return Status::kOk;
}

Status can_link_accept(int listen_fd, int timeout_ms, int& fd, std::string* error) {
  struct pollfd p;
  p.fd = listen_fd;
  p.events = POLLIN;
  p.revents = 0;
  const int rc = ::poll(&p, 1, timeout_ms);
  if (rc == 0) return Status::kEmpty;
  if (rc < 0) {
    if (error != nullptr) *error = errno_text("poll", errno);
    return Status::kIoError;
  }
  const int c = ::accept4(listen_fd, nullptr, nullptr, SOCK_CLOEXEC);
  if (c < 0) {
    if (error != nullptr) *error = errno_text("accept", errno);
    return Status::kIoError;
  }
  fd = c;
  return Status::kOk;
}

Status can_link_connect(const std::string& path, int& fd, std::string* error) {
  struct sockaddr_un addr;
  int c = -1;
  const Status s = seqpacket_socket(path, addr, c, error);
  if (!ok(s)) return s;
  if (::connect(c, reinterpret_cast<struct sockaddr*>(&addr), sizeof(addr)) != 0) {
    const int err = errno;
    if (error != nullptr) *error = errno_text(("connect " + path).c_str(), err);
    ::close(c);
    return err == ENOENT || err == ECONNREFUSED ? Status::kNotFound : Status::kIoError;
  }
  fd = c;
  return Status::kOk;
}

Status can_link_pair(int& fd_a, int& fd_b) {
  int sv[2];
  if (::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, sv) != 0) return Status::kIoError;
  fd_a = sv[0];
  fd_b = sv[1];
  return Status::kOk;
}

}  // namespace uwbnav::hal
