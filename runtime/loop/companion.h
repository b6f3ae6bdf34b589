// A second sensor with a model of its own, fused into the run's poses
// (fusion.companion in the configuration; docs/configuration.md, "A second
// sensor"): typically a LiDAR with the BEV model beside a camera with the
// image model -- the camera is better by day, the LiDAR does not care about
// light (docs/evaluation.md, "The LiDAR model").
//
// The companion is described by a configuration file of its own, the one
// that runs it alone (its model, source, extrinsics, sanity limits and
// validity gate), so its gate keeps the limits chosen for its model. Its
// capture thread fills its own frame slot at its own rate; the inference
// thread, after the run's own estimate of a cycle, runs the companion's model
// on its newest frame if a new one came (poll), then takes its latest
// estimate moved onto the cycle's time by the companion's own track (at) and
// fuses the two (runtime/pose/sensor_fusion.h).
//
// @rt: poll() and at() allocate nothing, take no lock and never wait.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "runtime/config/config.h"
#include "runtime/engine/engine.h"
#include "runtime/loop/capture.h"
#include "runtime/loop/estimator.h"
#include "runtime/loop/pose_record.h"
#include "runtime/pose/sensor_fusion.h"

namespace aprt {

// A pose record's estimate as the fusion takes it: base_link, variances from
// the model's own sigma for the frame, else from `sigma_pos_m` / `sigma_rot_rad`
// (the model's validation error). @rt.
SensorEstimate sensor_estimate(const PoseRecord& rec, uint32_t flags, double sigma_pos_m,
                               double sigma_rot_rad) noexcept;

// The sigma an estimate has when its model gives none for the frame: the
// configured output.sigma_*, else the model's validation error, else 1 m / 0.1 rad.
void fallback_sigma(const Config& config, const ModelMeta& meta, double* position_m,
                    double* rotation_rad);

// `fused` written back into the record: base_link, and the pose and sigma of
// the trigger sensor mounted at `base_from_sensor` (console, errors, covariance). @rt.
void write_fused(const SensorEstimate& fused, const Eigen::Isometry3d& base_from_sensor,
                 PoseRecord* rec) noexcept;

class Companion {
 public:
  // `config`: the companion's own configuration, its paths resolved;
  // `max_age_ms`: the run's fusion.companion_max_age_ms.
  static Expected<std::unique_ptr<Companion>> create(const Config& config, double max_age_ms);

  CaptureChannel& channel() { return *channel_; }
  const CaptureChannel& channel() const { return *channel_; }
  const Engine& engine() const { return *engine_; }
  const Config& config() const { return config_; }

  // Inference thread: the newest frame, if one came since the last call,
  // through the companion's model and its own checks and gate. @rt.
  void poll() noexcept;
  // Its latest estimate as of `capture_ns` (the cycle's frame, CLOCK_MONOTONIC):
  // moved by its confirmed track's motion over the time between the two
  // frames; not present when none is younger than companion_max_age_ms. @rt.
  SensorEstimate at(int64_t capture_ns) const noexcept;
  // The capture time of the frame behind the latest estimate (0: none yet).
  int64_t latest_capture_ns() const { return latest_capture_ns_; }

  struct Stats {
    uint64_t estimates = 0, valid = 0;      // its frames run, and how many its gate passed
    uint64_t used[4] = {};                  // the run's poses by FusedFrom (sensor_fusion.h)
    uint64_t disagreements = 0, stale = 0;  // both valid and apart; no recent estimate
    double age_sum_ms = 0, age_max_ms = 0;  // of the estimates fused (recent enough)
  };
  Stats& stats() { return stats_; }
  const Stats& stats() const { return stats_; }

 private:
  Companion() = default;

  Config config_;
  std::unique_ptr<Engine> engine_;
  std::unique_ptr<CaptureChannel> channel_;
  CaptureChannel* channels_[1] = {};
  std::unique_ptr<Estimator> estimator_;
  double sigma_pos_m_ = 1, sigma_rot_rad_ = 0.1;  // when the model gives no sigma
  int64_t max_age_ns_ = 0;
  // The latest estimate and when its frame was taken.
  SensorEstimate latest_;
  int64_t latest_capture_ns_ = 0;
  double latest_gate_s_ = 0;  // on its gate's clock
  ValidStreak streak_;
  Stats stats_;
};

}  // namespace aprt
