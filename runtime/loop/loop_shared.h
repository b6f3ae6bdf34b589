// What the loop's threads share (runtime/loop/runtime.h has the threads):
// heartbeats, counters and the supervisor's state, each written by one
// thread and read by others, all atomics -- no lock anywhere.
#pragma once

#include <atomic>
#include <cstdint>

#include "runtime/loop/pose_record.h"
#include "runtime/loop/spsc_ring.h"

namespace aprt {

// A state change as the supervisor made it (reason: a static string).
struct StateChange {
  RunState state;
  const char* reason;
  int64_t at_ns;
};

struct LoopShared {
  // supervisor -> publish thread: state changes to print in order with the
  // poses (one console stream; output.console). A full ring drops the line.
  SpscRing<StateChange, 16> state_lines;
  std::atomic<bool> stop{false};
  // inference thread
  std::atomic<bool> inference_done{false};
  std::atomic<int64_t> inference_beat{0};
  std::atomic<int64_t> last_frame_ns{0};  // capture time of the newest frame inferred
  std::atomic<uint64_t> poses{0}, poses_flagged{0}, deadline_misses{0}, ring_full{0};
  std::atomic<uint32_t> last_flags{0};
  std::atomic<uint64_t> sparse_scans{0};  // LiDAR: scans too sparse for the model
  std::atomic<uint32_t> scan_points{0}, scan_dropped{0}, scan_clipped{0};  // the last scan
  // capture threads
  std::atomic<uint64_t> frames_skipped{0};
  // publish thread
  std::atomic<int64_t> publish_beat{0};
  std::atomic<uint64_t> published{0};
  std::atomic<uint64_t> output_errors{0};
  // supervisor
  std::atomic<uint8_t> state{uint8_t(RunState::kStarting)};
  std::atomic<const char*> reason{"starting"};  // static strings of the supervisor

  RunState run_state() const { return RunState(state.load(std::memory_order_relaxed)); }
};

// Every blocking wait of the loop is bounded by this.
inline constexpr int64_t kLoopWaitNs = 100 * 1000 * 1000;

}  // namespace aprt
