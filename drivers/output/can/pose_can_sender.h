// Sends one pose estimate per call as the DBC's frames, over any Channel:
// the E2E alive counter, the cycle limit, and what a real bus does to a
// sender -- TX queue full (a short bounded retry, then the rest of the
// estimate is dropped), interface down (counted, retried with the next
// estimate), interface gone (reopened at most once per recover interval),
// bus-off (nothing queued until the controller restarts; a probe per
// recover interval). Every outcome is counted; nothing here allocates,
// throws or blocks longer than the retry budget.
#pragma once

#include <cstdint>

#include "drivers/can/socketcan.h"
#include "drivers/output/can/pose_can_codec.h"

namespace aprt::can {

struct SenderOptions {
  Ids ids;
  bool fd = false;                  // one CAN FD frame instead of five classic frames
  int64_t cycle_ns = 0;             // at most one estimate per cycle (0: every estimate)
  int64_t recover_ns = 1000000000;  // bus-off probe / reopen interval
  int64_t retry_ns = 2000000;       // bounded wait for TX queue space per estimate
};

struct SenderStats {
  uint64_t estimates = 0;   // all frames of the estimate sent
  uint64_t frames = 0;      // frames sent
  uint64_t throttled = 0;   // skipped by the cycle limit
  uint64_t queue_full = 0;  // ENOBUFS/EAGAIN seen (before retry)
  uint64_t dropped = 0;     // estimates not (fully) sent
  uint64_t down = 0;        // writes refused: interface down
  uint64_t bus_off = 0;     // estimates held back by bus-off
  uint64_t errors = 0;      // other write errors
  uint64_t reopens = 0;     // successful reopen after the interface vanished
  BusState bus = BusState::kActive;
  bool link_down = false;
};

class PoseCanSender {
 public:
  enum class Outcome { kSent, kThrottled, kDropped };
  PoseCanSender(Channel* channel, const SenderOptions& options) : ch_(channel), o_(options) {}

  // @rt. `now_ns`: CLOCK_MONOTONIC.
  Outcome send(const PoseSignals& s, int64_t now_ns) noexcept;
  const SenderStats& stats() const { return st_; }
  // A short static description of the last problem ("" when healthy).
  const char* problem() const { return problem_; }
  uint8_t counter() const { return counter_; }

 private:
  bool write_all(const Frame* frames, int n) noexcept;
  Channel* ch_;
  SenderOptions o_;
  SenderStats st_;
  uint8_t counter_ = 0;
  int64_t last_sent_ns_ = 0, last_probe_ns_ = 0;
  bool sent_any_ = false, need_reopen_ = false, in_bus_off_ = false;
  const char* problem_ = "";
};

}  // namespace aprt::can
