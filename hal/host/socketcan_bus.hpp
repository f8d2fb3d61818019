// Linux SocketCAN board bus: a raw CAN socket (or any injected fd carrying the
// same struct can_frame / canfd_frame records, e.g. a Unix SOCK_SEQPACKET link
// between two processes), non-blocking, with error-frame decoding and counting.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "hal/hal.hpp"

namespace uwbnav::hal {

// Record sizes on the wire (sizeof struct can_frame / struct canfd_frame).
constexpr size_t kCanMtu = 16;
constexpr size_t kCanFdMtu = 72;

// CanFrame -> SocketCAN record in buf. Returns the record size (kCanMtu or
// kCanFdMtu) or 0 when the frame cannot be sent: FD frame with fd_enabled
// false, classic len > 8, FD len not a valid FD length (0..8,12,16,20,24,32,48,64).
size_t to_wire(const CanFrame& frame, bool fd_enabled, uint8_t (&buf)[kCanFdMtu]);
// SocketCAN record -> CanFrame (t_us untouched). kInvalidArgument when n is
// neither record size or the length field is out of range.
[[nodiscard]] Status from_wire(const uint8_t* buf, size_t n, CanFrame& out);

// One decoded SocketCAN error frame (linux/can/error.h).
struct CanErrorInfo {
  uint32_t classes = 0;       // CAN_ERR_* class bits (can_id without CAN_ERR_FLAG)
  bool tx_timeout = false;
  bool lost_arbitration = false;
  uint8_t lost_arbitration_bit = 0;  // data[0]
  bool controller = false;
  uint8_t controller_status = 0;     // data[1]: CAN_ERR_CRTL_*
  bool protocol = false;
  uint8_t protocol_type = 0;         // data[2]: CAN_ERR_PROT_*
  uint8_t protocol_location = 0;     // data[3]: CAN_ERR_PROT_LOC_*
  bool transceiver = false;
  uint8_t transceiver_status = 0;    // data[4]: CAN_ERR_TRX_*
  bool no_ack = false;
  bool bus_off = false;
  bool bus_error = false;
  bool restarted = false;
  bool has_error_counters = false;   // CAN_ERR_CNT
  uint8_t tx_error_count = 0;        // data[6]
  uint8_t rx_error_count = 0;        // data[7]
  bool rx_overflow = false;          // controller lost received frames
  bool tx_overflow = false;
  bool passive = false;              // reached error passive (rx or tx)
  bool warning = false;              // reached error warning (rx or tx)
  bool back_to_active = false;       // CAN_ERR_CRTL_ACTIVE
};
// Decodes an error frame (frame.flags has kFlagError; id holds the class bits).
CanErrorInfo decode_error_frame(const CanFrame& frame);
// Short human-readable summary, e.g. "bus-off controller(rx-passive)".
std::string describe_error(const CanErrorInfo& info);

struct CanErrorCounters {
  uint32_t tx_timeout = 0;
  uint32_t lost_arbitration = 0;
  uint32_t controller = 0;
  uint32_t protocol = 0;
  uint32_t transceiver = 0;
  uint32_t no_ack = 0;
  uint32_t bus_error = 0;
  uint32_t restarted = 0;
  uint32_t warning = 0;
  uint32_t passive = 0;
  uint8_t tx_error_count = 0;  // latest reported controller counters
  uint8_t rx_error_count = 0;
};

struct SocketCanOptions {
  bool fd = false;            // CAN_RAW_FD_FRAMES: send/receive CAN FD frames
  bool error_frames = true;   // subscribe to all error classes (CAN_RAW_ERR_FILTER)
  Clock* clock = nullptr;     // receive timestamps; nullptr: CLOCK_MONOTONIC
};

class SocketCanBus : public CanBus {
 public:
  SocketCanBus() = default;
  ~SocketCanBus() override;
  SocketCanBus(const SocketCanBus&) = delete;
  SocketCanBus& operator=(const SocketCanBus&) = delete;

  // Opens a raw CAN socket bound to `ifname` (e.g. "can0", "vcan0").
  // kUnsupported: the kernel has no AF_CAN (EAFNOSUPPORT) or no CAN FD support;
  // kNotFound: no such interface; kIoError: other failures. last_error() says why.
  [[nodiscard]] Status open(const std::string& ifname, const SocketCanOptions& options = {});
  // Takes ownership of a connected fd that carries can_frame/canfd_frame
  // records with message boundaries (SOCK_SEQPACKET link, socketpair) and makes it non-blocking.
  [[nodiscard]] Status adopt_fd(int fd, const SocketCanOptions& options = {});
  void close();
  bool is_open() const { return fd_ >= 0; }
  int fd() const { return fd_; }

  // kOk: queued by the kernel. kWouldBlock: EAGAIN/ENOBUFS (driver queue
  // full): frame dropped, counted in tx_dropped, never retried here (the next
  // cycle sends fresh data). kIoError: bus-off (after a CAN_ERR_BUSOFF error
  // frame, until CAN_ERR_RESTARTED), interface down or link closed: dropped and counted.
  // kInvalidArgument: frame not representable (see to_wire).
  [[nodiscard]] Status send(const CanFrame& frame) override;
  // kOk: next data frame, t_us = receive time. Error frames are decoded and
  // counted (counters(), error_counters(), last_error_frame()) and not returned.
  // kEmpty: nothing pending. kIoError: link closed / read failure.
  [[nodiscard]] Status receive(CanFrame& out) override;
  CanBusState state() const override { return state_; }
  const CanCounters& counters() const override { return counters_; }
  void reset_counters() override { counters_ = CanCounters{}; }

  const CanErrorCounters& error_counters() const { return errors_; }
  const CanErrorInfo& last_error_frame() const { return last_error_frame_; }
  const std::string& last_error() const { return last_error_; }

 private:
  void on_error_frame(const CanFrame& frame);
  uint64_t now_us() const;

  int fd_ = -1;
  bool can_socket_ = false;  // true: AF_CAN socket (SO_RXQ_OVFL available)
  SocketCanOptions options_;
  CanBusState state_ = CanBusState::kDown;
  CanCounters counters_;
  CanErrorCounters errors_;
  CanErrorInfo last_error_frame_;
  uint32_t rxq_dropped_ = 0;  // last SO_RXQ_OVFL value
  std::string last_error_;
};

// Link transport between two processes when SocketCAN is absent: a Unix-domain
// SOCK_SEQPACKET socket carrying the same records as a CAN_RAW socket. Wrap the
// connected fds with SocketCanBus::adopt_fd.
// listen: removes a stale socket file at `path`, binds and listens.
[[nodiscard]] Status can_link_listen(const std::string& path, int& listen_fd, std::string* error = nullptr);
// accept: waits up to timeout_ms (-1 forever) for the peer. kEmpty on timeout.
[[nodiscard]] Status can_link_accept(int listen_fd, int timeout_ms, int& fd, std::string* error = nullptr);
[[nodiscard]] Status can_link_connect(const std::string& path, int& fd, std::string* error = nullptr);
// A connected pair in one process (tests, threads).
[[nodiscard]] Status can_link_pair(int& fd_a, int& fd_b);

}  // namespace uwbnav::hal
