// The publish thread: every PoseRecord the inference thread pushed, in
// order, to the console (one line per pose) and to the outputs (DDS, CAN:
// runtime/loop/pose_outputs.h), the status at output.status_rate_hz, and
// the per-pose timing and ground-truth errors for the exit summary and the
// timing report (buffers sized at start, never grown).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "runtime/config/config.h"
#include "runtime/loop/fault_injector.h"
#include "runtime/loop/loop_shared.h"
#include "runtime/loop/pose_outputs.h"
#include "runtime/loop/pose_record.h"
#include "runtime/loop/run_stats.h"
#include "runtime/loop/spsc_ring.h"

namespace aprt {

using PoseRing = SpscRing<PoseRecord, 64>;

class Publisher {
 public:
  // capacity: how many poses' timings and errors are kept (later ones are not recorded).
  Publisher(const Config& config, PoseRing& ring, PoseOutputs& outputs, LoopShared& shared,
            const FaultInjector& faults, bool scans, size_t capacity);

  // The thread's body, until the inference thread is done (or stop) and the ring is empty.
  void run() noexcept;
  void set_started(int64_t started_ns) { started_ns_ = started_ns; }

  // After the thread ended.
  const TimingRecord* timings(size_t* count) const {
    *count = timing_count_;
    return timings_.data();
  }
  // Position (m) and orientation (deg) errors of the poses with ground truth.
  size_t errors(const float** position, const float** orientation) const {
    *position = pos_errors_.data();
    *orientation = rot_errors_.data();
    return error_count_;
  }
  uint64_t injected_publish_failures() const { return injected_publish_failures_; }
  // The supervisor's state changes not printed yet (the thread calls it
  // between poses; the runtime once more after the threads ended).
  void print_state_lines() const noexcept;

 private:
  void print_pose(const PoseRecord& r) const;
  void publish_status(double last_inference_ms, const FusionSummary& last_fusion,
                      const CompanionNote& last_companion, const FilterNote& last_filter) noexcept;

  const Config& config_;
  PoseRing& ring_;
  PoseOutputs& outputs_;
  LoopShared& shared_;
  const FaultInjector& faults_;
  bool scans_;
  int64_t started_ns_ = 0;
  std::vector<TimingRecord> timings_;
  size_t timing_count_ = 0;
  std::vector<float> pos_errors_, rot_errors_;
  size_t error_count_ = 0;
  uint64_t injected_publish_failures_ = 0;
};

// Angle between two unit quaternions (w x y z), degrees; yaw of one.
double quat_angle_deg(const double* a, const double* b);
double quat_yaw_deg(const double* q);

}  // namespace aprt
