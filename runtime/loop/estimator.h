// One cycle of the loop without its threads: the frames of one cycle (the
// trigger channel's and, with several cameras, the others') -> the engine's
// input (EngineInput) -> Engine::run -> decode_pose -> base_link -> fusion ->
// the checks that make a pose valid or flagged. The inference thread
// (runtime/loop/runtime.cc) calls it; tests can drive it alone.
//
// @rt: every call is bounded by the model and the camera count, allocates
// nothing and takes no lock.
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/input/frame.h"
#include "runtime/config/config.h"
#include "runtime/engine/engine.h"
#include "runtime/loop/capture.h"
#include "runtime/loop/odometry_input.h"
#include "runtime/loop/pose_record.h"
#include "runtime/pose/odometry_filter.h"
#include "runtime/pose/pose_fusion.h"
#include "runtime/pose/pose_gate.h"

namespace aprt {

// What the last LiDAR scan gave (diagnostics).
struct ScanNote {
  uint32_t points = 0, dropped = 0, clipped = 0;
  bool sparse = false;
};

// The validity gate's parameters from the configuration (sanity.track).
PoseGateParams pose_gate_params(const Config& config);
// The pose filter's (sanity.filter; its measurements chosen by sanity.track's
// limits; the fallback sigma of a model without confidence outputs).
OdometryFilterParams odometry_filter_params(const Config& config, const ModelMeta& meta);

class Estimator {
 public:
  // channels: the run's channels (configuration order), n of them.
  // meta: the running model's (the pose filter's sigma for a model without
  // confidence outputs, as `aprt eval` takes it).
  Estimator(const Config& config, const ModelMeta& meta, CaptureChannel* const* channels, size_t n);

  // Stamps rec with frame f's times and source and the inference's start;
  // returns kPoseStaleFrame when f waited longer than the supervisor's
  // frame_timeout_ms, else 0 (the run's cycle and a companion's alike).
  uint32_t start(const FrameBuffer& f, PoseRecord* rec) const noexcept;

  // Whether channel i's frame fits its engine input (a camera that
  // renegotiated is re-planned); false: the frame is skipped.
  bool fits(size_t i, const FrameBuffer& f) noexcept;

  // Runs `engine` on the cycle's frames (frames[i]: channel i's, or null
  // when it had none in time) and fills rec->pose, rec->base_* and, with
  // several cameras, rec->fusion; returns the cycle's loop flags so far
  // (sparse scan, no quorum). nan_output: fault injection (the first
  // camera's output becomes NaN).
  uint32_t infer(Engine& engine, const FrameBuffer* const* frames, bool nan_output,
                 PoseRecord* rec) noexcept;

  // The checks that need the whole cycle: the pose's own flags, the deadline
  // (rec's inference times), the jump from the last accepted pose, and the
  // validity gate (the model's confidence, the agreement with the motion:
  // runtime/pose/pose_gate.h); the history advances only with a pose that
  // passed. Returns all flags.
  // With sanity.filter the pose filter runs instead of the gate and rec's
  // pose becomes the filter's (runtime/pose/odometry_filter.h).
  uint32_t check(PoseRecord* rec, uint32_t flags) noexcept;

  // The live odometry the filter takes the frames' readings from (instead
  // of the frames' own); null: the frames'.
  void use_odometry(OdometryInput* in) { odometry_ = in; }

  const ScanNote& last_scan() const { return scan_; }
  // The validity gate, and the time (its clock) of the last estimate it checked.
  const PoseGate& gate() const { return gate_; }
  double last_gate_s() const { return last_gate_s_; }
  uint64_t sparse_scans() const { return sparse_scans_; }
  uint64_t no_quorum() const { return no_quorum_; }
  uint64_t deadline_misses() const { return deadline_misses_; }

 private:
  uint32_t write_input(size_t i, Engine& engine, const FrameBuffer& f) noexcept;

  CaptureChannel* const* channels_;
  size_t n_;
  float bounds_margin_;
  int min_points_;
  int64_t stale_ns_;
  int64_t deadline_ns_;
  FusionParams fusion_;
  PoseGate gate_;
  OdometryReading last_odometry_;
  OdometryInput* odometry_ = nullptr;  // the frame before's (the filter's motion is from it)
  OdometryFilter filter_{OdometryFilterParams{}, Eigen::Isometry3d::Identity()};
  GateClock clock_;  // the frames' own stamps where they have them
  double last_gate_s_ = 0;
  ScanNote scan_;
  uint64_t sparse_scans_ = 0, no_quorum_ = 0, deadline_misses_ = 0;
};

}  // namespace aprt
