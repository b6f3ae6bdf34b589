#include "drivers/output/can/pose_can_sender.h"

#include <cerrno>
#include <ctime>

namespace aprt::can {
namespace {

int64_t now_monotonic() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

}  // namespace

bool PoseCanSender::write_all(const Frame* frames, int n) noexcept {
  const int64_t give_up = now_monotonic() + o_.retry_ns;  // the real clock, not the caller's
  int sent = 0;
  while (sent < n) {
    const WriteResult r = ch_->write(frames[sent]);
    if (r == WriteResult::kSent) {
      ++sent;
      ++st_.frames;
      st_.link_down = false;
      continue;
    }
    if (r == WriteResult::kQueueFull) {
      ++st_.queue_full;
      if (now_monotonic() < give_up) {
        const timespec pause{0, 100000};  // 0.1 ms: a classic frame at 500 kbit/s is ~0.25 ms
        nanosleep(&pause, nullptr);
        continue;
      }
      problem_ = "TX queue full: estimate dropped (bus overloaded or no other node acknowledging)";
    } else if (r == WriteResult::kDown) {
      ++st_.down;
      st_.link_down = true;
      problem_ = "interface down: estimate not sent";
    } else {
      ++st_.errors;
      const int e = ch_->last_errno();
      if (e == ENXIO || e == ENODEV) {
        need_reopen_ = true;
        problem_ = "interface vanished: reopening";
      } else {
        problem_ = "write error: estimate dropped";
      }
    }
    break;
  }
  // The counter moves once per estimate that reached the bus at all, so a
  // receiver sees a partial estimate as incomplete and the next one in order.
  if (sent > 0) counter_ = uint8_t((counter_ + 1) & 0x0F);
  return sent == n;
}

PoseCanSender::Outcome PoseCanSender::send(const PoseSignals& s, int64_t now_ns) noexcept {
  if (o_.cycle_ns > 0 && sent_any_ && now_ns - last_sent_ns_ < o_.cycle_ns) {
    ++st_.throttled;
    return Outcome::kThrottled;
  }
  if (need_reopen_) {
    if (now_ns - last_probe_ns_ < o_.recover_ns) {
      ++st_.dropped;
      return Outcome::kDropped;
    }
    last_probe_ns_ = now_ns;
    if (!ch_->reopen()) {
      ++st_.dropped;
      return Outcome::kDropped;
    }
    need_reopen_ = false;
    ++st_.reopens;
    problem_ = "";
  }
  st_.bus = ch_->poll_bus();
  if (st_.bus == BusState::kBusOff) {
    // Queueing into a bus-off controller only fills the TX queue; probe once
    // per recover interval in case the restart notification was missed.
    if (!in_bus_off_) {
      in_bus_off_ = true;
      last_probe_ns_ = now_ns;
    }
    if (now_ns - last_probe_ns_ < o_.recover_ns) {
      ++st_.bus_off;
      ++st_.dropped;
      problem_ = "bus-off: estimates held back until the controller restarts";
      return Outcome::kDropped;
    }
    last_probe_ns_ = now_ns;
  } else {
    in_bus_off_ = false;
  }
  Frame frames[kClassicFrames];
  int n = 1;
  if (o_.fd) {
    encode_fd(s, counter_, o_.ids, &frames[0]);
  } else {
    n = encode_classic(s, counter_, o_.ids, frames);
  }
  if (!write_all(frames, n)) {
    ++st_.dropped;
    return Outcome::kDropped;
  }
  if (st_.bus != BusState::kBusOff) problem_ = "";
  ++st_.estimates;
  sent_any_ = true;
  last_sent_ns_ = now_ns;
  return Outcome::kSent;
}

}  // namespace aprt::can
