// Whether an estimate may go out as valid: no implausible jump from the last
// plausible pose, the model's own confidence for the frame, and the
// estimate's agreement with the vehicle's recent motion.
//
// An absolute pose regressor is right most of the time and, now and then,
// confidently on the wrong street (a view down one street looks like a view
// down another). An initialiser fed such a pose converges to the wrong place,
// so a pose is valid only when
//   - its 95 % position radius (the model's sigma, FORMAT.md 1.3) and its 95 %
//     yaw interval are within the configured limits (kPoseUncertain), and
//   - it continues a track of estimates that agree with a constant-velocity
//     motion: within a gate of the track's prediction in position and yaw
//     (kPoseInconsistent), the track having been confirmed by `confirm`
//     mutually consistent estimates in a row (kPoseUnconfirmed).
// Estimates that disagree do not move the track; after `lost_after` of them
// in a row the track is dropped and a new one must be confirmed -- a run of
// consistent estimates elsewhere (the vehicle really was elsewhere: a
// relocalisation) takes over the same way.
//
// Pure and allocation-free: the loop's estimator and `aprt eval` run the same
// gate over the same estimates.
#pragma once

#include <cstdint>

#include "runtime/base/angles.h"
#include "runtime/engine/pose_decode.h"
#include "runtime/pose/pose_flags.h"

namespace aprt {

struct PoseGateParams {
  double max_jump_m = 30.0;            // between plausible poses (0: off) ...
  double max_speed_mps = 60.0;         // ... plus this much per second between them
  bool enabled = true;                 // the confidence and track tests below
  double max_position_radius_m = 8.0;  // 95 % horizontal radius the model may state
  double max_yaw_interval_deg = 10.0;  // 95 % yaw half-interval
  double gate_m = 6.0;                 // distance from the track's prediction
  double gate_deg = 10.0;              // yaw difference from the track's prediction
  double gate_growth_mps = 2.0;        // the gate widens with the time since the last accepted
  int confirm = 5;                     // consistent estimates in a row that start a track
  int lost_after = 25;                 // rejections in a row that end it
};

// Whether the model's own 95 % regions for the estimate (its horizontal
// radius, its yaw half-interval) are within the limits: what makes an
// estimate usable at all (the gate's kPoseUncertain; the pose filter's
// measurements). An estimate without confidence outputs passes. @rt.
bool confident(const PoseEstimate& e, double max_radius_m, double max_yaw_deg) noexcept;

// The gate's clock in the loop. The motion gate compares poses against the
// time between their frames. A frame's own stamp (a PointCloud2 header, a
// recorded drive's stamp) is that time as the sensor saw it; arrival
// (capture_ns, CLOCK_MONOTONIC) is only as good as the machine's scheduling.
// So a recording replayed runs the gate on the clock it was recorded with and
// gives the same valid flags. A frame without a stamp is put on the stamps'
// clock by the last known offset between the two, so the clocks never mix
// (stamps that begin only after unstamped frames carry the origin over).
// Seconds since the first frame, from integer nanoseconds:
// a wall-clock stamp (~1.8e9 s) held in a double keeps only ~0.2 us. @rt.
class GateClock {
 public:
  double seconds(int64_t capture_ns, int64_t stamp_ns) noexcept {
    if (stamp_ns != 0) {
      const int64_t offset = stamp_ns - capture_ns;
      if (started_ && !stamped_) origin_ns_ += offset;  // the first stamp: onto its clock
      stamp_minus_capture_ns_ = offset;
      stamped_ = true;
    }
    const int64_t t = stamp_ns != 0 ? stamp_ns : capture_ns + stamp_minus_capture_ns_;
    if (!started_) {
      started_ = true;
      origin_ns_ = t;
    }
    return double(t - origin_ns_) * 1e-9;
  }

 private:
  int64_t origin_ns_ = 0, stamp_minus_capture_ns_ = 0;
  bool started_ = false, stamped_ = false;
};

class PoseGate {
 public:
  explicit PoseGate(const PoseGateParams& p = {}) : p_(p) {}

  // The gate's flags for an estimate at time t_s (seconds, on one clock: GateClock in the loop, the
  // drive's in eval) whose own flags are `flags` (an estimate already flagged is not used). @rt.
  uint32_t check(const PoseEstimate& e, double t_s, uint32_t flags) noexcept;
  // flags | check(): every flag the pose goes out with.
  uint32_t apply(const PoseEstimate& e, double t_s, uint32_t flags) noexcept {
    return flags | check(e, t_s, flags);
  }
  void reset() noexcept;

  bool tracking() const { return track_.count >= p_.confirm; }
  // The confirmed track's motion from time t0 to t1 (its constant-velocity
  // prediction at t1 minus at t0): false, and zeros, without a confirmed
  // track. Moves an estimate of this sensor onto another sensor's time. @rt.
  bool motion(double t0, double t1, double* dx, double* dy, double* dyaw) const noexcept;

  // A run of mutually consistent estimates: the newest kWindow of them (at
  // most kWindowS seconds back) give the constant-velocity prediction (least
  // squares in x, y and unwrapped yaw).
  struct Track {
    static constexpr int kWindow = 32;
    static constexpr double kWindowS = 1.5;
    double t[kWindow] = {}, x[kWindow] = {}, y[kWindow] = {}, yaw[kWindow] = {};
    int head = 0, size = 0;  // ring
    int count = 0;           // estimates it has taken in all
    int rejected = 0;        // estimates it refused in a row
    void clear() { head = size = count = rejected = 0; }
    void add(double t, double x, double y, double yaw) noexcept;
    // Predicted x, y, yaw at time tq.
    void predict(double tq, double max_speed, double* px, double* py, double* pyaw) const noexcept;
    double last_t() const { return t[(head + kWindow - 1) % kWindow]; }
    double last_yaw() const { return yaw[(head + kWindow - 1) % kWindow]; }
  };

 private:
  bool consistent(const Track& k, double t, double x, double y, double yaw) const noexcept;

  uint32_t gate(const PoseEstimate& e, double t_s, uint32_t flags) noexcept;
  uint32_t jump(const PoseEstimate& e, double t_s, uint32_t flags) noexcept;
  void remember(const PoseEstimate& e, double t_s) noexcept;

  PoseGateParams p_;
  bool have_prev_ = false;  // the last plausible pose, for the jump test
  double prev_[3] = {}, prev_t_ = 0;
  Track track_;      // confirmed when count >= confirm
  Track candidate_;  // estimates the track refused, agreeing among themselves
};

}  // namespace aprt
