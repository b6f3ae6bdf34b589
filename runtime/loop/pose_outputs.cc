#include "runtime/loop/pose_outputs.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "drivers/output/dds/dds_publisher.h"
#include "runtime/loop/recorder.h"
#include "runtime/pose/pose_filter.h"
#include "runtime/pose/pose_flags.h"
#include "runtime/pose/sensor_fusion.h"

namespace aprt {
namespace {

uint8_t diagnostic_level(RunState s) {
  switch (s) {
    case RunState::kRunning: return 0;  // OK
    case RunState::kStarting:
    case RunState::kDegraded: return 1;  // WARN
    case RunState::kFault: return 2;     // ERROR
    case RunState::kStopping: return 3;  // STALE
  }
  return 2;
}

}  // namespace

Expected<std::unique_ptr<PoseOutputs>> PoseOutputs::create(const Config& config,
                                                           const ModelMeta& meta) {
  std::unique_ptr<PoseOutputs> o(new (std::nothrow) PoseOutputs());
  if (!o) return Error(Errc::kOutOfMemory, "outputs: out of memory");
  o->cfg_ = config.output;
  const Config::Output& c = config.output;
  o->sigma_pos_ = c.sigma_position_m > 0 ? c.sigma_position_m
                  : meta.has_val_error   ? double(meta.val_error_position_m)
                                         : 0.0;
  o->sigma_rot_deg_ = c.sigma_orientation_deg > 0 ? c.sigma_orientation_deg
                      : meta.has_val_error        ? double(meta.val_error_orientation_deg)
                                                  : 0.0;
  const bool want_cov = c.dds.enabled || c.can.enabled;
  if (want_cov && (o->sigma_pos_ <= 0 || o->sigma_rot_deg_ <= 0)) {
    return Error(Errc::kInvalidArgument,
                 "%s: the model has no measured validation error (metadata val_error): set "
                 "output.sigma_position_m and output.sigma_orientation_deg for the published "
                 "covariance",
                 config.origin.c_str());
  }
  if (config.cameras.size() > 1) {
    for (const Config::Camera& cam : config.cameras)
      o->camera_keys_.push_back("camera " + cam.name);
  }
  const Config::Extrinsics& e = config.extrinsics;
  o->geometry_.reset(new (std::nothrow) PoseGeometry(
      RigidTransform::from_xyz_rpy(e.sensor_xyz, e.sensor_rpy_deg),
      RigidTransform::from_xyz_rpy(e.map_offset_xyz, e.map_offset_rpy_deg), o->sigma_pos_,
      o->sigma_rot_deg_ * M_PI / 180.0));
  if (!o->geometry_) return Error(Errc::kOutOfMemory, "outputs: out of memory");

  if (c.dds.enabled) {
    DdsOptions d;
    d.domain = uint32_t(c.dds.domain);
    d.pose_topic = c.dds.pose_topic;
    d.diagnostics_topic = c.dds.diagnostics_topic;
    d.frame_id = c.frame_id;
    d.reliable = c.dds.reliability == "reliable";
    d.depth = c.dds.depth;
    d.loopback_only = c.dds.loopback_only;
    d.discovery_wait_ms = c.dds.discovery_wait_ms;
    auto p = DdsPublisher::create(d);
    if (p) {
      o->dds_ = std::move(p.value());
      const DdsDiscoveryReport& f = o->dds_->discovery();
      if (f.pending > 0) {
        std::fprintf(stderr,
                     "aprt run: dds: %d of %d participants on domain %d told no endpoint within "
                     "discovery_wait_ms %d; their readers may miss the first poses\n",
                     f.pending, f.participants, c.dds.domain, c.dds.discovery_wait_ms);
      } else if (c.dds.discovery_wait_ms > 0) {
        std::fprintf(
            stderr, "aprt run: dds: %d participant%s on domain %d, endpoints known after %.0f ms\n",
            f.participants, f.participants == 1 ? "" : "s", c.dds.domain,
            double(f.waited_ns) / 1e6);
      }
    } else {
      o->dds_off_reason_ = p.error().message();
      std::fprintf(stderr, "aprt run: DDS output disabled: %s\n", p.error().message());
    }
  }
  if (c.can.enabled) {
    auto s = can::SocketCan::open(c.can.interface, c.can.fd, false);
    if (s) {
      o->can_socket_ = std::move(s.value());
    } else if (s.error().code() == Errc::kNotFound) {
      std::fprintf(stderr, "aprt run: %s; retrying every %.0f ms\n", s.error().message(),
                   c.can.recover_ms);
      o->can_socket_ = can::SocketCan::unbound(c.can.interface, c.can.fd, false);
    } else {
      o->can_off_reason_ = s.error().message();
      std::fprintf(stderr, "aprt run: CAN output disabled: %s\n", s.error().message());
    }
    if (o->can_socket_) {
      can::SenderOptions so;
      so.ids = {uint32_t(c.can.ids[0]), uint32_t(c.can.ids[1]), uint32_t(c.can.ids[2]),
                uint32_t(c.can.ids[3]), uint32_t(c.can.ids[4]), uint32_t(c.can.ids[5])};
      so.fd = c.can.fd;
      so.cycle_ns = int64_t(c.can.cycle_ms * 1e6);
      so.recover_ns = int64_t(c.can.recover_ms * 1e6);
      o->can_sender_.reset(new (std::nothrow) can::PoseCanSender(o->can_socket_.get(), so));
      if (!o->can_sender_) return Error(Errc::kOutOfMemory, "outputs: out of memory");
    }
  }
  return o;
}

PoseOutputs::~PoseOutputs() = default;

const can::SenderStats* PoseOutputs::can_stats() const {
  return can_sender_ ? &can_sender_->stats() : nullptr;
}

void PoseOutputs::publish(const PoseRecord& r, int64_t now_ns,
                          int64_t realtime_offset_ns) noexcept {
  if (!dds_ && !can_sender_ && !recorder_) return;
  last_ = geometry_->from_base(r.base_position, r.base_orientation);
  geometry_->covariance(r.pose, last_.covariance);
  const int64_t stamp_ns =
      r.source_stamp_ns ? r.source_stamp_ns : r.capture_ns + realtime_offset_ns;
  const bool valid = r.flags == 0 && r.state == RunState::kRunning;
  const double published_position[3] = {last_.position.x(), last_.position.y(), last_.position.z()};
  const double published_wxyz[4] = {last_.orientation.w(), last_.orientation.x(),
                                    last_.orientation.y(), last_.orientation.z()};
  if (recorder_) {
    RecordedPose p;
    p.stamp_ns = stamp_ns;
    p.index = r.index;
    p.frame_sequence = r.frame_sequence;
    p.flags = r.flags;
    p.state = uint8_t(r.state);
    p.published = valid;
    std::memcpy(p.position, published_position, sizeof p.position);
    std::memcpy(p.orientation, published_wxyz, sizeof p.orientation);
    std::memcpy(p.covariance, last_.covariance, sizeof p.covariance);
    std::memcpy(p.estimate_position, r.pose.position, sizeof p.estimate_position);
    std::memcpy(p.estimate_orientation, r.pose.orientation, sizeof p.estimate_orientation);
    p.capture_ns = r.capture_ns;
    p.inference_start_ns = r.inference_start_ns;
    p.inference_end_ns = r.inference_end_ns;
    p.publish_ns = now_ns;
    recorder_->offer_pose(p);
  }
  if (dds_) {
    if (valid) {
      DdsPose p;
      p.stamp_ns = stamp_ns;
      std::memcpy(p.position, published_position, sizeof p.position);
      std::memcpy(p.orientation, published_wxyz, sizeof p.orientation);
      std::memcpy(p.covariance, last_.covariance, sizeof p.covariance);
      if (dds_->publish_pose(p)) {
        ++stats_.dds_poses;
      } else {
        ++stats_.dds_errors;
      }
    } else {
      ++stats_.dds_withheld;
      if (r.state != RunState::kRunning) ++stats_.dds_withheld_not_running;
      for (int bit = 0; bit < 16; ++bit) {
        if (r.flags & (1u << bit)) ++stats_.dds_withheld_flag[bit];
      }
    }
  }
  if (can_sender_) {
    can::PoseSignals s;
    s.state = uint8_t(r.state);
    s.flags = uint16_t(r.flags & 0xFFFF);
    s.valid = valid;
    // The pose's own confidence (FORMAT.md 1.3) where the model has it: the
    // horizontal 1-sigma (the larger axis, after the map offset: the
    // covariance's x-y block) and the yaw 1-sigma; else the constant.
    if (r.pose.has_sigma) {
      s.sigma_pos_m = std::sqrt(std::max(last_.covariance[0], last_.covariance[7]));
      s.sigma_yaw_deg = std::sqrt(last_.covariance[35]) * 180.0 / M_PI;
    } else {
      s.sigma_pos_m = sigma_pos_;
      s.sigma_yaw_deg = sigma_rot_deg_;
    }
    s.x = last_.position.x();
    s.y = last_.position.y();
    s.z = last_.position.z();
    s.qw = last_.orientation.w();
    s.qx = last_.orientation.x();
    s.qy = last_.orientation.y();
    s.qz = last_.orientation.z();
    s.timestamp_us = stamp_ns > 0 ? uint64_t(stamp_ns / 1000) : 0;
    switch (can_sender_->send(s, now_ns)) {
      case can::PoseCanSender::Outcome::kSent: ++stats_.can_sent; break;
      case can::PoseCanSender::Outcome::kThrottled: ++stats_.can_throttled; break;
      case can::PoseCanSender::Outcome::kDropped: ++stats_.can_dropped; break;
    }
  }
}

void PoseOutputs::publish_status(const StatusSnapshot& s, int64_t realtime_ns) noexcept {
  if (!dds_ && !recorder_) return;
  enum {
    kState,
    kReason,
    kPoses,
    kFlagged,
    kFlags,
    kLate,
    kSkipped,
    kInfer,
    kCan,
    kCanSent,
    kCanDropped,
    kCanProblem,
    kCount
  };
  static const char* const kKeys[kCount] = {
      "state",          "reason",       "poses", "flagged",       "last_flags",  "deadline_misses",
      "frames_skipped", "inference_ms", "can",   "can_estimates", "can_dropped", "can_problem"};
  // Multi-camera runs add "fusion" and one "camera NAME" per camera; LiDAR runs
  // "lidar"; runs with a second sensor "companion".
  constexpr int kMax = kCount + 6 + 8;
  const char* keys[kMax];
  char v[kMax][96];
  for (int i = 0; i < kCount; ++i) keys[i] = kKeys[i];
  std::snprintf(v[kState], sizeof v[0], "%s", run_state_name(s.state));
  std::snprintf(v[kReason], sizeof v[0], "%s", s.reason);
  std::snprintf(v[kPoses], sizeof v[0], "%llu", static_cast<unsigned long long>(s.poses));
  std::snprintf(v[kFlagged], sizeof v[0], "%llu", static_cast<unsigned long long>(s.flagged));
  std::snprintf(v[kFlags], sizeof v[0], "0x%04x", s.last_flags);
  std::snprintf(v[kLate], sizeof v[0], "%llu", static_cast<unsigned long long>(s.deadline_misses));
  std::snprintf(v[kSkipped], sizeof v[0], "%llu",
                static_cast<unsigned long long>(s.frames_skipped));
  std::snprintf(v[kInfer], sizeof v[0], "%.1f", s.last_inference_ms);
  const can::SenderStats* cs = can_stats();
  if (cs) {
    std::snprintf(v[kCan], sizeof v[0], "%s %s%s", cfg_.can.interface.c_str(),
                  can::bus_state_name(cs->bus), cs->link_down ? " link-down" : "");
    std::snprintf(v[kCanSent], sizeof v[0], "%llu", static_cast<unsigned long long>(cs->estimates));
    std::snprintf(v[kCanDropped], sizeof v[0], "%llu",
                  static_cast<unsigned long long>(cs->dropped));
    std::snprintf(v[kCanProblem], sizeof v[0], "%s", can_sender_->problem());
  } else {
    std::snprintf(v[kCan], sizeof v[0], "%s", cfg_.can.enabled ? "unavailable" : "off");
    v[kCanSent][0] = v[kCanDropped][0] = '\0';
    std::snprintf(v[kCanProblem], sizeof v[0], "%s", can_off_reason_.c_str());
  }
  int count = kCount;
  if (s.lidar) {
    keys[count] = "lidar";
    std::snprintf(v[count++], sizeof v[0], "%u points, %u dropped, %u clipped; %llu sparse",
                  s.scan_points, s.scan_dropped, s.scan_clipped,
                  static_cast<unsigned long long>(s.sparse_scans));
  }
  const FusionSummary* f = s.fusion;
  if (!camera_keys_.empty() && f) {
    keys[count] = "fusion";
    std::snprintf(v[count++], sizeof v[0], "%u/%u agree, spread %.2f m %.2f deg",
                  unsigned(f->inliers), unsigned(camera_keys_.size()), double(f->spread_m),
                  double(f->spread_deg));
    for (size_t i = 0; i < camera_keys_.size() && count < kMax; ++i) {
      keys[count] = camera_keys_[i].c_str();
      if (std::isnan(f->deviation_m[i])) {
        std::snprintf(v[count++], sizeof v[0], "%s",
                      i < f->cameras ? "no usable estimate" : "no cycle yet");
      } else {
        std::snprintf(v[count++], sizeof v[0], "%s %.2f m %.2f deg",
                      (f->inlier_mask >> i) & 1 ? "inlier" : "outlier", double(f->deviation_m[i]),
                      double(f->deviation_deg[i]));
      }
    }
  }
  if (s.companion && s.companion->configured) {
    const CompanionNote& cn = *s.companion;
    keys[count] = "companion";
    if (!cn.present) {
      std::snprintf(v[count++], sizeof v[0], "no recent estimate");
    } else {
      std::snprintf(v[count++], sizeof v[0], "%s, %.1f m %.1f deg apart, %.0f ms old",
                    fused_from_name(FusedFrom(cn.from)), double(cn.distance_m),
                    double(cn.yaw_diff_deg), double(cn.age_ms));
      keys[count] = "companion_flags";
      pose_flag_names(cn.flags, v[count++], int(sizeof v[0]));
    }
  }
  if (s.filter && s.filter->configured && count < kMax) {
    // "fix, 95 % 2.1 m 1.4 deg; estimate taken" / "no fix; estimate refused (3 in a row)"
    const FilterNote& fn = *s.filter;
    keys[count] = "filter";
    char regions[32] = "no fix";
    if (fn.fix) {
      std::snprintf(regions, sizeof regions, "fix, 95 %% %.1f m %.1f deg", double(fn.radius95_m),
                    double(fn.yaw95_deg));
    }
    std::snprintf(v[count++], sizeof v[0], "%s; %s", regions,
                  PoseFilter::use_name(PoseFilter::Use(fn.use)));
    if (fn.refused > 1 && count < kMax) {
      keys[count] = "filter_refused";
      std::snprintf(v[count++], sizeof v[0], "%u in a row", unsigned(fn.refused));
    }
  }
  const char* values[kMax];
  for (int i = 0; i < count; ++i) values[i] = v[i];
  char message[128];
  std::snprintf(message, sizeof message, "%s: %s", run_state_name(s.state), s.reason);
  if (recorder_) {
    recorder_->offer_status(realtime_ns, diagnostic_level(s.state), message, keys, values, count);
  }
  if (!dds_) return;
  if (dds_->publish_status(realtime_ns, diagnostic_level(s.state), message, keys, values, count)) {
    ++stats_.dds_status;
  } else {
    ++stats_.dds_errors;
  }
}

void withheld_reasons(const OutputStats& st, char* buf, size_t size) {
  buf[0] = '\0';
  if (st.dds_withheld == 0) return;
  size_t used = 0;
  const auto put = [&](const char* fmt, unsigned long long n, const char* what) {
    if (used < size) used += size_t(std::snprintf(buf + used, size - used, fmt, n, what));
  };
  put(" (%llu %s", st.dds_withheld_not_running, "supervisor not RUNNING");
  const char* sep = "; ";
  for (int bit = 0; bit < 16; ++bit) {
    if (!st.dds_withheld_flag[bit]) continue;
    const char* name = kPoseFlagNames[bit] ? kPoseFlagNames[bit] : "other";
    if (used < size) used += size_t(std::snprintf(buf + used, size - used, "%s", sep));
    put("%llu %s", st.dds_withheld_flag[bit], name);
    sep = ", ";
  }
  if (used < size) std::snprintf(buf + used, size - used, ")");
}

void PoseOutputs::print_summary() const {
  if (cfg_.dds.enabled) {
    if (dds_) {
      char why[512];
      withheld_reasons(stats_, why, sizeof why);
      std::printf("dds: %llu poses published on rt%s, %llu withheld%s, %llu errors\n",
                  static_cast<unsigned long long>(stats_.dds_poses), cfg_.dds.pose_topic.c_str(),
                  static_cast<unsigned long long>(stats_.dds_withheld), why,
                  static_cast<unsigned long long>(stats_.dds_errors));
    } else {
      std::printf("dds: disabled (%s)\n", dds_off_reason_.c_str());
    }
  }
  if (cfg_.can.enabled) {
    if (const can::SenderStats* c = can_stats()) {
      std::printf(
          "can: %s: %llu estimates sent (%llu frames), %llu dropped, %llu throttled; queue full "
          "%llu, link down %llu, bus-off %llu, errors %llu, reopened %llu; bus %s\n",
          cfg_.can.interface.c_str(), static_cast<unsigned long long>(c->estimates),
          static_cast<unsigned long long>(c->frames), static_cast<unsigned long long>(c->dropped),
          static_cast<unsigned long long>(c->throttled),
          static_cast<unsigned long long>(c->queue_full), static_cast<unsigned long long>(c->down),
          static_cast<unsigned long long>(c->bus_off), static_cast<unsigned long long>(c->errors),
          static_cast<unsigned long long>(c->reopens), can::bus_state_name(c->bus));
    } else {
      std::printf("can: disabled (%s)\n", can_off_reason_.c_str());
    }
  }
}

}  // namespace aprt
