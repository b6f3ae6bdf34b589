// The end of a run, for a person: the summary `aprt run` prints at exit
// (frames, poses, latency, per-camera and LiDAR counts, errors against
// ground truth). Off the real-time path: it sorts and allocates.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "runtime/loop/run_stats.h"

namespace aprt {

struct RunSummary {
  const RunStats* stats = nullptr;
  const TimingRecord* timings = nullptr;
  size_t timing_count = 0;
  const float* position_errors = nullptr;     // m, of the poses with ground truth
  const float* orientation_errors = nullptr;  // deg
  size_t error_count = 0;
  const char* isa = "";
  int threads = 1;
  bool lidar = false;
  std::vector<std::string> camera_names;  // more than one: a fused run
  const char* memory = "";                // memory_budget_text(), or empty
};

void print_run_summary(const RunSummary& s);

// The p-quantile (0..1) of v, nearest rank.
double quantile(std::vector<double> v, double p);

}  // namespace aprt
