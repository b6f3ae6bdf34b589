#include "runtime/loop/companion.h"

#include <cmath>
#include <cstdio>
#include <new>

#include "runtime/base/clock.h"
#include "runtime/loop/model_loader.h"
#include "runtime/pose/pose_fusion.h"

namespace aprt {

SensorEstimate sensor_estimate(const PoseRecord& rec, uint32_t flags, double sigma_pos_m,
                               double sigma_rot_rad) noexcept {
  SensorEstimate e;
  e.present = true;
  e.flags = flags;
  for (int k = 0; k < 3; ++k) e.position[k] = rec.base_position[k];
  e.orientation = Eigen::Quaterniond(rec.base_orientation[0], rec.base_orientation[1],
                                     rec.base_orientation[2], rec.base_orientation[3]);
  const PoseEstimate& p = rec.pose;
  for (int k = 0; k < 3; ++k) {
    const double s = p.has_sigma ? p.sigma_position_m[k] : sigma_pos_m;
    e.var_position[k] = s * s;
  }
  const double sy = p.has_sigma ? p.sigma_rotation_rad[2] : sigma_rot_rad;
  e.var_yaw = sy * sy;
  if (!e.position.allFinite() || !e.orientation.coeffs().allFinite() || !std::isfinite(e.var_yaw) ||
      !(e.var_yaw > 0) || !(e.var_position[0] > 0) || !(e.var_position[1] > 0) ||
      !(e.var_position[2] > 0)) {
    // Nothing invented: such an estimate is never fused and never valid.
    e.flags |= kPoseNonFinite;
    for (double& v : e.var_position) v = 1e12;
    e.var_yaw = 1e12;
  }
  return e;
}

void fallback_sigma(const Config& config, const ModelMeta& meta, double* position_m,
                    double* rotation_rad) {
  *position_m = 1.0;
  *rotation_rad = 0.1;
  if (meta.has_val_error) {
    *position_m = double(meta.val_error_position_m);
    *rotation_rad = double(meta.val_error_orientation_deg) * M_PI / 180.0;
  }
  if (config.output.sigma_position_m > 0) *position_m = config.output.sigma_position_m;
  if (config.output.sigma_orientation_deg > 0) {
    *rotation_rad = config.output.sigma_orientation_deg * M_PI / 180.0;
  }
}

void write_fused(const SensorEstimate& fused, const Eigen::Isometry3d& base_from_sensor,
                 PoseRecord* rec) noexcept {
  const PoseEstimate before = rec->pose;
  for (int k = 0; k < 3; ++k) rec->base_position[k] = fused.position[k];
  rec->base_orientation[0] = fused.orientation.w();
  rec->base_orientation[1] = fused.orientation.x();
  rec->base_orientation[2] = fused.orientation.y();
  rec->base_orientation[3] = fused.orientation.z();
  rec->pose = base_to_sensor(fused.position, fused.orientation, base_from_sensor);
  rec->pose.flags = fused.flags;
  // The published covariance follows the estimate that went out: the fused
  // variances per map axis and in yaw; roll and pitch keep the run's own.
  rec->pose.has_sigma = true;
  for (int k = 0; k < 3; ++k) {
    rec->pose.sigma_position_m[k] = std::sqrt(fused.var_position[k]);
    rec->pose.sigma_rotation_rad[k] =
        before.has_sigma ? before.sigma_rotation_rad[k] : std::sqrt(fused.var_yaw);
  }
  rec->pose.sigma_rotation_rad[2] = std::sqrt(fused.var_yaw);
}

Expected<std::unique_ptr<Companion>> Companion::create(const Config& config, double max_age_ms) {
  std::unique_ptr<Companion> c(new (std::nothrow) Companion());
  if (!c) return Error(Errc::kOutOfMemory, "run: out of memory");
  c->config_ = config;
  c->max_age_ns_ = int64_t(max_age_ms * 1e6);
  const Config& cfg = c->config_;
  std::string note;
  auto engine = load_model(model_request(cfg), &note);
  if (!engine) {
    return Error(engine.error().code(), "fusion.companion %s: %s", cfg.origin.c_str(),
                 engine.error().message());
  }
  if (!note.empty()) std::fprintf(stderr, "aprt run: %s: %s\n", cfg.model.c_str(), note.c_str());
  c->engine_ = std::move(engine.value());
  std::vector<Config::Camera> cams = camera_list(cfg);
  cams[0].name = "companion";
  size_t frames = 0;
  auto ch = open_channel(cams[0], 0, 1, *c->engine_, cfg.model, &frames);
  if (!ch) {
    return Error(ch.error().code(), "fusion.companion %s: %s", cfg.origin.c_str(),
                 ch.error().message());
  }
  c->channel_ = std::move(ch.value());
  c->channel_->thread_name = "aprt-companion";
  c->channels_[0] = c->channel_.get();
  c->estimator_.reset(new (std::nothrow) Estimator(cfg, c->engine_->meta(), c->channels_, 1));
  if (!c->estimator_) return Error(Errc::kOutOfMemory, "run: out of memory");
  fallback_sigma(cfg, c->engine_->meta(), &c->sigma_pos_m_, &c->sigma_rot_rad_);
  return c;
}

void Companion::poll() noexcept {
  CaptureChannel& ch = *channel_;
  const FrameBuffer* f = nullptr;
  if (!ch.slot->take(&f)) return;
  if (ch.replay()) ch.source->note_taken(f->info.sequence + 1);
  if (!estimator_->fits(0, *f)) return;
  PoseRecord rec;
  const uint32_t stale = estimator_->start(*f, &rec);
  const FrameBuffer* frames[1] = {f};
  uint32_t flags = estimator_->infer(*engine_, frames, false, &rec) | stale;
  rec.inference_end_ns = monotonic_ns();
  flags = estimator_->check(&rec, flags);
  latest_ = sensor_estimate(rec, flags, sigma_pos_m_, sigma_rot_rad_);
  latest_capture_ns_ = rec.capture_ns;
  latest_gate_s_ = estimator_->last_gate_s();
  latest_.valid_for_s = streak_.update(latest_.flags == 0, latest_gate_s_);
  ++stats_.estimates;
  if (latest_.flags == 0) ++stats_.valid;
}

SensorEstimate Companion::at(int64_t capture_ns) const noexcept {
  SensorEstimate e = latest_;
  const int64_t age_ns = capture_ns - latest_capture_ns_;
  if (!latest_.present || std::llabs(age_ns) > max_age_ns_) {
    e.present = false;
    return e;
  }
  const double age_s = double(age_ns) * 1e-9;
  double dx = 0, dy = 0, dyaw = 0;
  if (estimator_->gate().motion(latest_gate_s_, latest_gate_s_ + age_s, &dx, &dy, &dyaw)) {
    e.position.x() += dx;
    e.position.y() += dy;
    e.orientation =
        (Eigen::AngleAxisd(dyaw, Eigen::Vector3d::UnitZ()) * e.orientation).normalized();
    // The prediction's own error grows with the time it bridges.
    const double g = config_.sanity.track.gate_growth_mps * std::fabs(age_s);
    e.var_position[0] += g * g;
    e.var_position[1] += g * g;
  }
  e.valid_for_s += age_s > 0 ? age_s : 0;
  return e;
}

}  // namespace aprt
