// A raw SocketCAN endpoint (classic CAN or CAN FD) for the pose sender and
// the decoder tool. Writes never block: a full TX queue (ENOBUFS/EAGAIN) and
// a down interface (ENETDOWN) come back as results the caller counts; the
// controller's error frames (bus-off, error-passive, restarted) are read
// without blocking and summarised as a bus state.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "drivers/can/can_frame.h"
#include "runtime/base/expected.h"

namespace aprt::can {

enum class WriteResult { kSent, kQueueFull, kDown, kError };

enum class BusState : uint8_t { kActive, kWarning, kPassive, kBusOff };
const char* bus_state_name(BusState s);

// What the pose sender needs from a CAN endpoint (tests substitute a fake).
class Channel {
 public:
  virtual ~Channel() = default;
  // @rt: non-blocking.
  virtual WriteResult write(const Frame& f) noexcept = 0;
  // @rt: drains pending error frames; returns the bus state they imply.
  virtual BusState poll_bus() noexcept = 0;
  // @rt: reopens the socket after the interface vanished (ENODEV); true when bound again.
  virtual bool reopen() noexcept = 0;
  virtual const char* name() const noexcept = 0;
  // errno of the last kError/kDown (for messages).
  int last_errno() const noexcept { return last_errno_; }

 protected:
  int last_errno_ = 0;
};

class SocketCan final : public Channel {
 public:
  // `fd`: enable CAN FD frames (the interface's MTU must be 72).
  // `receive`: also receive data frames (the decoder tool); the sender only
  // receives error frames.
  static Expected<std::unique_ptr<SocketCan>> open(const std::string& interface, bool fd,
                                                   bool receive);
  // Not yet bound (the interface does not exist yet): writes fail with
  // ENODEV until reopen() succeeds -- a sender retries per recover interval.
  static std::unique_ptr<SocketCan> unbound(const std::string& interface, bool fd, bool receive);
  ~SocketCan() override;
  SocketCan(const SocketCan&) = delete;
  SocketCan& operator=(const SocketCan&) = delete;

  WriteResult write(const Frame& f) noexcept override;
  BusState poll_bus() noexcept override;
  bool reopen() noexcept override;
  const char* name() const noexcept override { return interface_; }

  // Waits at most timeout_ms for a frame. 1: *f filled (error frames come
  // back with id | kErrorFrameFlag), 0: timeout, -1: error (last_errno()).
  int read(Frame* f, int timeout_ms, int64_t* timestamp_ns) noexcept;
  static constexpr uint32_t kErrorFrameFlag = 0x20000000u;

  // A reader: the kernel queues only data frames with these ids (11-bit or
  // 29-bit; 1 to kMaxFilterIds), so a busy bus does not wake the reader for
  // frames it would drop. Kept across reopen().
  static constexpr int kMaxFilterIds = 8;
  Status set_filter(const uint32_t* ids, int n) noexcept;

  // Error-frame classes seen since open (cumulative).
  uint64_t bus_off_events = 0, passive_events = 0, warning_events = 0, restarted_events = 0;
  uint64_t lost_arbitration = 0, tx_timeouts = 0;

 private:
  SocketCan() = default;
  Status bind_socket() noexcept;
  void note_error_frame(const uint8_t* data, uint32_t id) noexcept;
  int fd_ = -1;
  char interface_[16] = {};
  bool want_fd_ = false, receive_ = false;
  uint32_t filter_ids_[kMaxFilterIds] = {};
  int filter_count_ = 0;
  Status apply_filter(int fd) const noexcept;
  BusState state_ = BusState::kActive;
};

}  // namespace aprt::can
