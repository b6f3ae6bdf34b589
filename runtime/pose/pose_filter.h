// The published pose from the estimates and the vehicle's own motion: an
// extended Kalman filter over base_link's planar pose (x, y, yaw), carried
// from frame to frame by the odometry (drivers/input/odometry.h) and corrected
// by each estimate the model is confident in and that agrees with it.
//
// Why: an absolute pose regressor's single frames are metres off and, now and
// then, on the wrong street (a view down one street looks like a view down
// another, a corner shows only a wall). The constant-velocity track of the
// validity gate (pose_gate.h) can refuse such estimates but cannot bridge
// them: it loses every sharp turn. With the vehicle's motion known to a few
// per cent, the filter
//   - averages many frames' estimates into one pose (their errors shrink),
//   - rejects an estimate whose Mahalanobis distance from the prediction is
//     beyond a chi-square gate (the estimate's own covariance plus the
//     filter's),
//   - keeps publishing through frames whose estimates are uncertain or
//     refused, its covariance growing with the distance travelled, until it
//     is too large to be valid,
//   - starts only from `confirm` estimates that agree with each other along
//     the odometry, and lets such a run elsewhere take over only after
//     `take_over_after` refusals in a row (a relocalisation).
// A pose is valid when the filter has a fix and its own 95 % horizontal
// radius and yaw interval are within the limits: the covariance published is
// the filter's, not the single estimate's, with the estimates' mean
// disagreement with it added (disagreement_frames). With place_sigma_m the
// state also holds the bias the estimates of one place share.
//
// Pure, allocation-free, fixed-size state: the loop's estimator and `aprt
// eval` run the same filter over the same estimates.
#pragma once

#include <cstdint>

#include "drivers/input/odometry.h"

namespace aprt {

struct PoseFilterParams {
  bool enabled = false;
  // The odometry's error, one standard deviation: what each step adds to
  // the covariance.
  double distance_noise = 0.05;      // of the distance travelled (slip, tyre radius)
  double yaw_noise_deg_per_m = 0.5;  // heading per metre travelled (slip in turns)
  double yaw_rate_noise_dps = 0.2;   // heading per second (the gyro's bias)
  double gate_chi2 = 11.34;          // Mahalanobis distance^2 an estimate may have (3 dof: 99 %)
  int confirm = 4;                   // estimates agreeing along the odometry that start a fix
  int take_over_after = 25;          // refusals in a row before another run may take over
  double max_radius_m = 8.0;         // the filter's 95 % horizontal radius to publish valid
  double max_yaw_deg = 5.0;          // the filter's 95 % yaw half-interval to publish valid
  double lost_radius_m = 100.0;      // a fix whose 95 % radius grows beyond this is dropped
  // The published position sigma is the filter's times this, calibrated on
  // validation drives: the estimates' sigmas (calibrated per frame, heavy
  // tail included) overstate the error of the ones the filter takes.
  double position_sigma_scale = 1.0;
  // An estimate's position sigma as the filter weighs it: the model's times
  // this. The model's sigma is calibrated to cover 95 % of all its frames,
  // the wrong-street ones included; the filter refuses those at its gate, so
  // the ones it takes are overstated by that tail (calibrated on validation).
  double estimate_sigma_scale = 1.0;
  // The time constant, in estimates taken, of the running mean of the
  // estimates' disagreement with the filter (their innovations), whose outer
  // product is added to the filter's position covariance (0: off). Why: the
  // estimates' errors are correlated over many frames in places (a stretch of
  // views the model places a few metres short), which a filter assuming
  // independent estimates follows and then believes; unbiased estimates
  // average to no disagreement, a filter that is off by b sees the estimates
  // disagree by about -b on average, so the published covariance (and
  // validity) take in what the estimates measure against it.
  int disagreement_frames = 0;
  // The part of the estimates' error that stays with the place (0: off): a
  // bias of this standard deviation per horizontal axis, shared by the
  // estimates of views less than about `place_length_m` apart (a first-order
  // Gauss-Markov process in the distance driven), estimated beside the pose.
  // Why: on the town's validation drives about half of the model's error
  // variance is correlated over ~5 m of road (docs/evaluation.md), and a
  // filter that averages such estimates as independent believes a mean that
  // does not shrink. With the bias in the state the filter weighs a run of
  // estimates from one place as what it is -- one view's worth of evidence
  // about the place's offset -- and its covariance says so.
  double place_sigma_m = 0.0;
  double place_length_m = 5.0;
};

// The model's stated confidence an estimate may have for the odometry filter
// (odometry_filter.h) to take it at all; sanity.filter's keys of these names.
struct EstimateLimits {
  double estimate_max_radius_m = 60.0;  // the model's 95 % horizontal radius
  double estimate_max_yaw_deg = 30.0;   // ... and its 95 % yaw half-interval
};

// A planar estimate of base_link in the map with one standard deviation per axis.
struct PlanarPose {
  double x = 0, y = 0, yaw = 0;
  double sigma_x = 0, sigma_y = 0, sigma_yaw = 0;  // m, m, rad
};

class PoseFilter {
 public:
  // Why a step's estimate did or did not move the filter (diagnostics).
  enum class Use : uint8_t { kNone, kAccepted, kRefused, kStarted, kTookOver };

  struct Output {
    bool fix = false;    // the filter has a pose (else `pose` is the estimate, if any)
    uint32_t flags = 0;  // kPoseUnconfirmed, kPoseUncertain, kPoseNoOdometry; 0: valid
    PlanarPose pose;     // the filter's pose and its 1-sigma (the covariance's diagonal)
    double cov_xy = 0;   // the covariance's x-y term (m^2)
    double radius95_m = -1, yaw95_deg = -1;  // the published 95 % regions (-1: no fix)
    Use use = Use::kNone;
    int refused = 0;  // estimates refused in a row
  };

  explicit PoseFilter(const PoseFilterParams& p = {}) : p_(p) {}

  // One frame: `motion` is base_link's since the previous step (null: not
  // known -- the fix is dropped, flag kPoseNoOdometry); `estimate` this
  // frame's, when usable as a measurement (null: none, or not confident). @rt.
  Output step(const PlanarMotion* motion, const PlanarPose* estimate) noexcept;
  void reset() noexcept;

  bool has_fix() const { return fix_.count > 0; }
  static const char* use_name(Use u);

 private:
  struct State {
    double s[5] = {};   // x, y, yaw, and the estimates' place bias in x and y
    double P[25] = {};  // row-major covariance (the bias rows zero when place_sigma_m is 0)
    int count = 0;      // estimates taken (0: empty)
    double d[2] = {};   // running mean of the position innovations taken (disagreement_frames)
  };
  void predict(State* k, const PlanarMotion& m) const noexcept;
  // The estimate's Mahalanobis distance^2 from k; with `update`, k takes it.
  double innovation(const State& k, const PlanarPose& z, bool update, State* out) const noexcept;
  State start(const PlanarPose& z) const noexcept;
  Output output(const State& k, uint32_t flags) const noexcept;

  PoseFilterParams p_;
  State fix_;        // the published filter (count >= confirm)
  State candidate_;  // estimates the fix refused (or before any), agreeing among themselves
  int refused_ = 0;
};

}  // namespace aprt
