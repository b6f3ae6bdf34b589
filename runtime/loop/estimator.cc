#include "runtime/loop/estimator.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "runtime/base/clock.h"
#include "runtime/loop/companion.h"

namespace aprt {

Estimator::Estimator(const Config& config, const ModelMeta& meta, CaptureChannel* const* channels,
                     size_t n)
    : channels_(channels),
      n_(n),
      bounds_margin_(float(config.sanity.bounds_margin)),
      min_points_(config.source.lidar.min_points),
      stale_ns_(int64_t(config.supervisor.frame_timeout_ms * 1e6)),
      deadline_ns_(int64_t(config.supervisor.inference_deadline_ms * 1e6)) {
  fusion_.max_position_spread_m = config.fusion.max_position_spread_m;
  fusion_.max_orientation_spread_rad = config.fusion.max_orientation_spread_deg * M_PI / 180.0;
  fusion_.min_agreeing = config.fusion.min_agreeing;
  gate_ = PoseGate(pose_gate_params(config));
  filter_ = OdometryFilter(odometry_filter_params(config, meta),
                           n > 0 ? channels[0]->base_from_sensor : Eigen::Isometry3d::Identity());
}

uint32_t Estimator::start(const FrameBuffer& f, PoseRecord* rec) const noexcept {
  rec->inference_start_ns = monotonic_ns();
  rec->capture_ns = f.info.capture_ns;
  rec->source_stamp_ns = f.info.source_stamp_ns;
  rec->frame_sequence = f.info.sequence;
  rec->source = f.info.source;
  rec->odometry = f.info.odometry;
  return rec->inference_start_ns - f.info.capture_ns > stale_ns_ ? kPoseStaleFrame : 0;
}

PoseGateParams pose_gate_params(const Config& config) {
  const Config::Sanity::Track& t = config.sanity.track;
  PoseGateParams p;
  p.enabled = t.enabled;
  p.max_position_radius_m = t.max_radius_m;
  p.max_yaw_interval_deg = t.max_yaw_deg;
  p.gate_m = t.gate_m;
  p.gate_deg = t.gate_deg;
  p.gate_growth_mps = t.gate_growth_mps;
  p.max_jump_m = config.sanity.max_jump_m;
  p.max_speed_mps = config.sanity.max_speed_mps;
  p.confirm = t.confirm;
  p.lost_after = t.lost_after;
  return p;
}

OdometryFilterParams odometry_filter_params(const Config& config, const ModelMeta& meta) {
  const Config::Sanity::Filter& f = config.sanity.filter;
  OdometryFilterParams p;
  p.filter = f;                         // the filter's own part
  static_cast<EstimateLimits&>(p) = f;  // and what it takes at all
  fallback_sigma(config, meta, &p.fallback_sigma_m, &p.fallback_sigma_rad);
  return p;
}

bool Estimator::fits(size_t i, const FrameBuffer& f) noexcept {
  const CaptureChannel& c = *channels_[i];
  return c.scans() || c.input->fit(f.info.format, f.info.width, f.info.height);
}

// A scan (with the running model's geometry: a reloaded model keeps its
// input, reload_compatible refuses another) or an image into the input.
uint32_t Estimator::write_input(size_t i, Engine& engine, const FrameBuffer& f) noexcept {
  EngineInput& in = *channels_[i]->input;
  if (!in.scans()) {
    in.write_image(f.view(), engine);
    return 0;
  }
  const ScanInputResult r = in.write_scan(f.points(), f.info.scan.points, engine);
  scan_.points = uint32_t(r.points);
  scan_.dropped = f.info.scan.non_finite + f.info.scan.over_capacity;
  scan_.clipped = f.info.scan.clipped;
  scan_.sparse = !r.enough || r.points < size_t(min_points_);
  if (!scan_.sparse) return 0;
  ++sparse_scans_;
  return kPoseSparseScan;
}

uint32_t Estimator::infer(Engine& engine, const FrameBuffer* const* frames, bool nan_output,
                          PoseRecord* rec) noexcept {
  const ModelMeta& m = engine.meta();
  uint32_t flags = 0;
  CameraEstimate est[kMaxFusedCameras];
  for (size_t i = 0; i < n_; ++i) {
    if (!frames[i]) continue;
    flags |= write_input(i, engine, *frames[i]);
    (void)engine.run();
    if (i == 0 && nan_output) engine.output().f32()[0] = std::numeric_limits<float>::quiet_NaN();
    const PoseEstimate p = decode_pose(engine.output().f32(), m, bounds_margin_);
    est[i] = camera_to_base(p, channels_[i]->base_from_sensor);
    if (n_ == 1) {
      rec->pose = p;
      break;
    }
    if (p.flags) ++channels_[i]->flagged;
  }
  const CaptureChannel& trigger = *channels_[0];
  if (n_ == 1) {
    // A pose whose base_link transform is not finite keeps the sensor pose's flags.
    for (int k = 0; k < 3; ++k) rec->base_position[k] = est[0].position[k];
    const Eigen::Quaterniond& q = est[0].orientation;
    rec->base_orientation[0] = q.w();
    rec->base_orientation[1] = q.x();
    rec->base_orientation[2] = q.y();
    rec->base_orientation[3] = q.z();
    return flags;
  }
  const FusionResult fr = fuse_poses(est, int(n_), fusion_);
  for (int k = 0; k < 3; ++k) rec->base_position[k] = fr.position[k];
  rec->base_orientation[0] = fr.orientation.w();
  rec->base_orientation[1] = fr.orientation.x();
  rec->base_orientation[2] = fr.orientation.y();
  rec->base_orientation[3] = fr.orientation.z();
  // The console and the errors against ground truth speak of the trigger
  // camera: the fused pose as it would have seen it.
  rec->pose = base_to_sensor(fr.position, fr.orientation, trigger.base_from_sensor);
  if (!fr.valid) {
    uint32_t camera_flags = 0;
    for (size_t i = 0; i < n_; ++i) camera_flags |= est[i].present ? est[i].flags : 0;
    rec->pose.flags = camera_flags;
    flags |= kPoseNoQuorum;
    ++no_quorum_;
  }
  FusionSummary& fs = rec->fusion;
  fs.cameras = uint8_t(n_);
  fs.present = uint8_t(fr.present);
  fs.usable = uint8_t(fr.usable);
  fs.inliers = uint8_t(fr.inliers);
  fs.inlier_mask = fr.inlier_mask;
  fs.spread_m = float(fr.spread_m);
  fs.spread_deg = float(fr.spread_deg);
  for (size_t i = 0; i < n_; ++i) {
    fs.deviation_m[i] = float(fr.deviation_m[i]);
    fs.deviation_deg[i] = float(fr.deviation_deg[i]);
    if (est[i].present && est[i].flags == 0 && !(fr.inlier_mask & (1u << i))) {
      ++channels_[i]->outliers;
    }
  }
  return flags;
}

uint32_t Estimator::check(PoseRecord* rec, uint32_t flags) noexcept {
  flags |= rec->pose.flags;
  if (rec->inference_end_ns - rec->inference_start_ns > deadline_ns_) {
    flags |= kPoseDeadlineMissed;
    ++deadline_misses_;
  }
  // A frame that came late or stale says nothing against the track's motion;
  // everything else the pose itself or the fusion flagged is not used by it.
  const uint32_t own = flags & ~(kPoseStaleFrame | kPoseDeadlineMissed);
  last_gate_s_ = clock_.seconds(rec->capture_ns, rec->source_stamp_ns);
  if (!filter_.enabled()) return flags | gate_.check(rec->pose, last_gate_s_, own);
  // The filter's pose goes out instead of the estimate: valid by its own
  // covariance, whatever this frame's estimate was; a late or stale frame
  // still withholds it.
  if (odometry_) {
    // The frame's time on the twists' clock (ROS time): its own stamp, or
    // its capture time moved onto the realtime clock.
    const int64_t t = rec->source_stamp_ns != 0
                          ? rec->source_stamp_ns
                          : rec->capture_ns + (realtime_ns() - monotonic_ns());
    rec->odometry = odometry_->reading_at(t);
  }
  PlanarMotion motion;
  const bool moved = motion_between(last_odometry_, rec->odometry, &motion);
  last_odometry_ = rec->odometry;
  const FilteredPose fp = filter_.step(rec->pose, flags, moved ? &motion : nullptr);
  rec->pose = fp.sensor;
  FilterNote& note = rec->filter;
  note.configured = true;
  note.fix = fp.fix;
  note.use = uint8_t(fp.use);
  note.refused = uint16_t(fp.refused < 65535 ? fp.refused : 65535);
  note.radius95_m = float(fp.radius95_m);
  note.yaw95_deg = float(fp.yaw95_deg);
  for (int k = 0; k < 3; ++k) rec->base_position[k] = fp.base_position[k];
  for (int k = 0; k < 4; ++k) rec->base_orientation[k] = fp.base_orientation[k];
  return (flags & (kPoseStaleFrame | kPoseDeadlineMissed)) | fp.flags;
}

}  // namespace aprt
