// The timing validation report of a run (`aprt run --timing FILE.json`):
// per-stage latency statistics from the per-pose timestamps the publish
// thread records into a buffer sized at start, plus what the process did to
// memory after it reached steady state. Written after the run, never on the
// real-time path. A CSV of the raw timestamps goes beside the JSON for
// plotting (python3 -m aprt_tools plot-timing).
#pragma once

#include <cstddef>
#include <cstdint>

#include "runtime/base/expected.h"

namespace aprt {

struct TimingRecord;
struct RunStats;
struct MemoryBudget;

// Process memory and allocation figures sampled by the supervisor.
struct MemorySample {
  bool valid = false;
  uint64_t allocations = 0;  // process-wide count (allocation_counter.h)
  uint64_t rss_kb = 0;       // resident set (/proc/self/statm)
};

struct TimingContext {
  const char* model = "";
  const char* source = "";
  const char* isa = "";
  int threads = 1;
  double camera_period_ms = 0;       // 0: replay as fast as inference (no camera period)
  double inference_deadline_ms = 0;  // supervisor.inference_deadline_ms
  bool allocations_counted = false;  // an allocation counter is linked in
  bool counter_covers_malloc = false;
  MemorySample steady;  // after the first published pose
  MemorySample warm;    // after warmup_poses (invalid when the run was shorter)
  uint64_t warmup_poses = 0;
  MemorySample end;  // after the last
  uint64_t peak_rss_kb = 0;
  const MemoryBudget* budget = nullptr;  // where the memory is, or null
  double duration_s = 0;
};

struct StageStats {
  double min, median, p99, p999, max, mean;
  size_t count;
};

// Statistics of `n` values in ms; sorts a copy, so call it off the real-time path.
StageStats stage_stats(const double* values_ms, size_t n);

// Writes `json_path` and, beside it, the same name with ".csv".
Status write_timing_report(const char* json_path, const TimingRecord* records, size_t n,
                           const RunStats& stats, const TimingContext& ctx);

// Resident set size of this process in KiB (0 if /proc is unreadable), and its peak.
uint64_t current_rss_kb();
uint64_t peak_rss_kb();

}  // namespace aprt
