#include "runtime/loop/publisher.h"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "runtime/base/angles.h"
#include "runtime/base/clock.h"
#include "runtime/pose/pose_gate.h"
#include "runtime/pose/sensor_fusion.h"

namespace aprt {

double quat_yaw_deg(const double* q) {
  return quaternion_yaw(q) * 180.0 / M_PI;
}

double quat_angle_deg(const double* a, const double* b) {
  double d = 0;
  for (int i = 0; i < 4; ++i) d += a[i] * b[i];
  return 2.0 * std::acos(std::min(1.0, std::fabs(d))) * 180.0 / M_PI;
}

Publisher::Publisher(const Config& config, PoseRing& ring, PoseOutputs& outputs, LoopShared& shared,
                     const FaultInjector& faults, bool scans, size_t capacity)
    : config_(config),
      ring_(ring),
      outputs_(outputs),
      shared_(shared),
      faults_(faults),
      scans_(scans),
      // Sized (and so written, every page resident) here, not grown by
      // push_back: the loop then touches no new memory, which the soak's RSS
      // check relies on.
      timings_(capacity),
      pos_errors_(capacity),
      rot_errors_(capacity) {}

void Publisher::publish_status(double last_inference_ms, const FusionSummary& last_fusion,
                               const CompanionNote& last_companion,
                               const FilterNote& last_filter) noexcept {
  StatusSnapshot st;
  st.state = shared_.run_state();
  st.reason = shared_.reason.load(std::memory_order_acquire);
  st.poses = shared_.poses.load(std::memory_order_relaxed);
  st.flagged = shared_.poses_flagged.load(std::memory_order_relaxed);
  st.deadline_misses = shared_.deadline_misses.load(std::memory_order_relaxed);
  st.frames_skipped = shared_.frames_skipped.load(std::memory_order_relaxed);
  st.last_flags = shared_.last_flags.load(std::memory_order_relaxed);
  st.last_inference_ms = last_inference_ms;
  st.fusion = &last_fusion;
  st.companion = &last_companion;
  st.filter = &last_filter;
  if (scans_) {
    st.lidar = true;
    st.scan_points = shared_.scan_points.load(std::memory_order_relaxed);
    st.scan_dropped = shared_.scan_dropped.load(std::memory_order_relaxed);
    st.scan_clipped = shared_.scan_clipped.load(std::memory_order_relaxed);
    st.sparse_scans = shared_.sparse_scans.load(std::memory_order_relaxed);
  }
  outputs_.publish_status(st, realtime_ns());
}

// The supervisor's state changes, on the console's stream between the poses.
void Publisher::print_state_lines() const noexcept {
  StateChange c;
  bool any = false;
  while (shared_.state_lines.pop(&c)) {
    std::printf("aprt run: state %s (%s)\n", run_state_name(c.state), c.reason);
    any = true;
  }
  if (any) std::fflush(stdout);
}

void Publisher::run() noexcept {
  PoseRecord r;
  const int64_t status_period = int64_t(1e9 / config_.output.status_rate_hz);
  int64_t next_status = monotonic_ns();
  double last_inference_ms = 0;
  FusionSummary last_fusion;
  CompanionNote last_companion;
  FilterNote last_filter;
  for (;;) {
    shared_.publish_beat.store(monotonic_ns(), std::memory_order_release);
    if (monotonic_ns() >= next_status) {
      next_status += status_period;
      publish_status(last_inference_ms, last_fusion, last_companion, last_filter);
    }
    print_state_lines();
    if (!ring_.pop(&r)) {
      if (shared_.inference_done.load(std::memory_order_acquire) && ring_.size() == 0) break;
      if (shared_.stop.load(std::memory_order_acquire) && ring_.size() == 0) break;
      const timespec ts{0, 1000000};  // 1 ms: publishing tolerates this much added latency
      nanosleep(&ts, nullptr);
      continue;
    }
    const int64_t now = monotonic_ns();
    if (config_.output.console) print_pose(r);
    // The frame's monotonic capture time in wall-clock time, for the stamps.
    if (faults_.publish_failure(r.index)) {
      ++injected_publish_failures_;
    } else {
      outputs_.publish(r, now, realtime_ns() - now);
    }
    shared_.output_errors.store(outputs_.stats().dds_errors + injected_publish_failures_,
                                std::memory_order_release);
    last_inference_ms = double(r.inference_end_ns - r.inference_start_ns) * 1e-6;
    last_fusion = r.fusion;
    last_companion = r.companion;
    last_filter = r.filter;
    if (timing_count_ < timings_.size()) {
      timings_[timing_count_++] = {r.capture_ns, r.inference_start_ns, r.inference_end_ns, now,
                                   r.flags};
    }
    shared_.published.fetch_add(1, std::memory_order_release);
    if (r.has_truth && error_count_ < pos_errors_.size()) {
      double d = 0;
      for (int k = 0; k < 3; ++k) {
        d +=
            (r.pose.position[k] - r.truth_position[k]) * (r.pose.position[k] - r.truth_position[k]);
      }
      pos_errors_[error_count_] = float(std::sqrt(d));
      rot_errors_[error_count_++] = float(quat_angle_deg(r.pose.orientation, r.truth_orientation));
    }
  }
}

void Publisher::print_pose(const PoseRecord& r) const {
  char flags[160];
  pose_flag_names(r.flags, flags, sizeof flags);
  const auto add = [&](const char* what) {
    std::strncat(flags, what, sizeof flags - std::strlen(flags) - 1);
  };
  if (r.fusion.cameras > 1) {  // agreeing / configured cameras
    char cams[24];
    std::snprintf(cams, sizeof cams, " cams %u/%u", unsigned(r.fusion.inliers),
                  unsigned(r.fusion.cameras));
    add(cams);
  }
  if (r.companion.configured) {  // whose estimate went out: own, companion or both
    add(r.companion.from == uint8_t(FusedFrom::kBoth)        ? " from both"
        : r.companion.from == uint8_t(FusedFrom::kCompanion) ? " from companion"
        : r.companion.present                                ? " from own"
                                                             : " from own (companion stale)");
  }
  if (std::strncmp(flags, "ok,", 3) == 0)
    std::memmove(flags, flags + 3, std::strlen(flags + 3) + 1);
  const double t = double(r.capture_ns - started_ns_) * 1e-9;
  const double ms = double(r.inference_end_ns - r.inference_start_ns) * 1e-6;
  const double* p = r.pose.position;
  if (r.has_truth) {
    double d = 0;
    for (int k = 0; k < 3; ++k) d += (p[k] - r.truth_position[k]) * (p[k] - r.truth_position[k]);
    std::printf(
        "%6llu %7.2fs  x %8.2f y %8.2f z %6.2f  yaw %7.1f  err %6.2f m %6.1f deg  %5.1f ms  %-9s "
        "%s\n",
        static_cast<unsigned long long>(r.frame_sequence), t, p[0], p[1], p[2],
        quat_yaw_deg(r.pose.orientation), std::sqrt(d),
        quat_angle_deg(r.pose.orientation, r.truth_orientation), ms, run_state_name(r.state),
        flags);
  } else {
    std::printf("%6llu %7.2fs  x %8.2f y %8.2f z %6.2f  yaw %7.1f  %5.1f ms  %-9s %s\n",
                static_cast<unsigned long long>(r.frame_sequence), t, p[0], p[1], p[2],
                quat_yaw_deg(r.pose.orientation), ms, run_state_name(r.state), flags);
  }
}

}  // namespace aprt
