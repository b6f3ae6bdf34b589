// What a run did, for the exit summary and the timing report
// (runtime/loop/run_report.h, timing_report.h).
#pragma once

#include <cstdint>
#include <vector>

namespace aprt {

// Per-frame stage timings (monotonic ns), recorded by the publish thread.
struct TimingRecord {
  int64_t capture_ns, inference_start_ns, inference_end_ns, publish_ns;
  uint32_t flags;  // the pose's (runtime/pose/pose_flags.h)
};

struct RunStats {
  uint64_t frames_captured = 0, frames_skipped = 0, frames_dropped = 0;
  uint64_t poses = 0, poses_flagged = 0, deadline_misses = 0, ring_full = 0;
  uint64_t source_restarts = 0;
  uint64_t reloads = 0, reloads_refused = 0;
  uint64_t publish_failures_injected = 0;
  // Multi-camera runs: fusion cycles without a quorum, and per camera
  // (configuration order) frames captured, cycles it had no frame in time,
  // estimates flagged, and estimates rejected as outliers.
  uint64_t fusion_no_quorum = 0;
  uint64_t sparse_scans = 0;  // LiDAR: scans with too few points (flagged estimates)
  struct Camera {
    uint64_t frames = 0, missing = 0, flagged = 0, outliers = 0, dropped = 0;
  };
  std::vector<Camera> cameras;
};

}  // namespace aprt
