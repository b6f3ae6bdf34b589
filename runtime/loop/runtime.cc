#include "runtime/loop/runtime.h"

#include <fcntl.h>
#include <linux/watchdog.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "drivers/replay/replay_source.h"
#include "runtime/engine/model_input.h"
#include "runtime/loop/model_loader.h"
#include "runtime/loop/open_source.h"

namespace aprt {
namespace {

constexpr int64_t kWaitNs = 100 * 1000 * 1000;  // every blocking wait is bounded by this

// systemd's notification protocol (sd_notify(3)): one datagram to $NOTIFY_SOCKET.
void sd_notify_text(const char* text) {
  const char* path = std::getenv("NOTIFY_SOCKET");
  if (!path || !*path) return;
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  const size_t n = std::strlen(path);
  if (n >= sizeof addr.sun_path) return;
  std::memcpy(addr.sun_path, path, n);
  if (addr.sun_path[0] == '@') addr.sun_path[0] = '\0';  // abstract namespace
  const int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return;
  sendto(fd, text, std::strlen(text), MSG_NOSIGNAL, reinterpret_cast<sockaddr*>(&addr),
         socklen_t(offsetof(sockaddr_un, sun_path) + n));
  close(fd);
}

int64_t realtime_ns() {
  timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return int64_t(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

double yaw_deg(const double* q) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  return std::atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)) * 180.0 / M_PI;
}

double angle_deg(const double* a, const double* b) {
  double d = 0;
  for (int i = 0; i < 4; ++i) d += a[i] * b[i];
  return 2.0 * std::acos(std::min(1.0, std::fabs(d))) * 180.0 / M_PI;
}

template <class T>
double percentile(std::vector<T> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return double(v[std::min(v.size() - 1, size_t(p * double(v.size() - 1) + 0.5))]);
}

}  // namespace

Expected<std::unique_ptr<Runtime>> Runtime::create(const Config& config) {
  std::unique_ptr<Runtime> r(new (std::nothrow) Runtime());
  if (!r) return Error(Errc::kOutOfMemory, "run: out of memory");
  r->config_ = config;
  r->supervisor_ = Supervisor(config.supervisor);
  std::string note;
  auto engine = load_model(config, &note);
  if (!engine) return engine.error();
  if (!note.empty()) std::fprintf(stderr, "aprt run: %s: %s\n", config.model.c_str(), note.c_str());
  r->engine_ = std::move(engine.value());
  if (Status s = r->faults_.configure(config.fault_injection); !s) return s.error();
  if (r->faults_.any()) {
    std::fprintf(stderr, "aprt run: %zu deliberate fault(s) configured (fault_injection)\n",
                 config.fault_injection.size());
  }

  const std::vector<Config::Camera> cams = camera_list(config);
  if (cams.size() > size_t(kMaxFusedCameras)) {
    return Error(Errc::kInvalidArgument, "run: at most %d cameras", kMaxFusedCameras);
  }
  size_t frames = 0;  // the first replay's length
  const kernels::PreprocessParams pp = preprocess_params(r->engine_->meta());
  for (size_t i = 0; i < cams.size(); ++i) {
    const Config::Camera& cam = cams[i];
    auto ch = std::unique_ptr<Channel>(new (std::nothrow) Channel());
    if (!ch) return Error(Errc::kOutOfMemory, "run: out of memory");
    ch->owner = r.get();
    ch->index = i;
    ch->name = cam.name;
    ch->thread_name = cams.size() == 1 ? "aprt-capture" : "aprt-cap" + std::to_string(i);
    ch->source_type = cam.source.type;
    ch->base_from_sensor =
        RigidTransform::from_xyz_rpy(cam.sensor_xyz, cam.sensor_rpy_deg).isometry();
    const Config::Source& src = cam.source;
    // Before any device is opened: a camera model needs a camera, a LiDAR model a LiDAR.
    if (Status fit = model_fits_source(r->engine_->meta(), src, config.model); !fit) {
      return fit.error();
    }
    auto opened = open_source(src);
    if (!opened) {
      if (cams.size() == 1) return opened.error();
      return Error(opened.error().code(), "run: camera %s: %s", cam.name.c_str(),
                   opened.error().message());
    }
    const int width = opened->width, height = opened->height;
    const PixelFormat format = opened->format;
    if (i == 0) frames = opened->frames;
    ch->scans = src.lidar_source();
    ch->source = std::move(opened->source);
    auto slot = FrameSlot::create(ch->source->max_frame_bytes());
    if (!slot) return slot.error();
    ch->slot = std::move(slot.value());
    if (ch->replay() && src.replay.rate_hz == 0 && !src.replay.recorded) {
      ch->source->pace_with(ch->slot.get());
    }
    const format::Modality modality = r->engine_->meta().modality;
    if (ch->scans) {
      const size_t max_points = size_t(src.lidar.max_points);
      if (modality == format::Modality::kLidarPoints) {
        r->points_input_ = points_input_params(r->engine_->meta());
        r->scan_scratch_.resize(
            kernels::lidar_points_input_scratch(max_points, r->points_input_.samples));
      } else {
        r->bev_input_ = bev_input_params(r->engine_->meta());
        r->bev_counts_.resize(size_t(r->bev_input_.bev.grid) * r->bev_input_.bev.grid * 2);
      }
      r->cameras_.push_back(std::move(ch));
      continue;
    }
    ch->plan.reset(new (std::nothrow) kernels::PreprocessPlan());
    const kernels::KernelSet* ks = r->engine_->kernel_set();
    if (!ch->plan || !kernels::plan_preprocess(pp, format, width, height, ch->plan.get(),
                                               ks ? ks->preprocess : nullptr)) {
      return Error(Errc::kInvalidArgument,
                   "run: camera %s: cannot map %dx%d frames to the model's %dx%d input",
                   cam.name.c_str(), width, height, pp.size, pp.size);
    }
    r->cameras_.push_back(std::move(ch));
  }
  auto outputs = PoseOutputs::create(config, r->engine_->meta());
  if (!outputs) return outputs.error();
  r->outputs_ = std::move(outputs.value());
  r->ring_.reset(new (std::nothrow) SpscRing<PoseRecord, 64>());
  if (!r->ring_) return Error(Errc::kOutOfMemory, "run: out of memory");
  // Per-pose records for the summary and --timing: the run's length when it is
  // known, else 2^20 poses (9.7 h at 30 Hz; later poses are not recorded).
  const bool replay = config.source.type == "replay" || config.source.type == "lidar_replay";
  const size_t capacity = replay && config.source.replay.frames > 0
                              ? size_t(config.source.replay.frames) + 16
                          : replay && !config.source.replay.loop ? frames + 16
                                                                 : size_t(1) << 20;
  r->timings_.resize(capacity);
  // Sized (and so written, every page resident) here, not grown by push_back:
  // the loop then touches no new memory, which the soak's RSS check relies on.
  r->pos_errors_.resize(capacity);
  r->rot_errors_.resize(capacity);
  if (!config.supervisor.watchdog_device.empty()) {
    r->watchdog_fd_ = open(config.supervisor.watchdog_device.c_str(), O_WRONLY | O_CLOEXEC);
    if (r->watchdog_fd_ < 0) {
      return Error(Errc::kIo, "run: cannot open watchdog %s: %s",
                   config.supervisor.watchdog_device.c_str(), std::strerror(errno));
    }
    int timeout = config.supervisor.watchdog_timeout_s;
    if (ioctl(r->watchdog_fd_, WDIOC_SETTIMEOUT, &timeout) != 0) {
      std::fprintf(stderr,
                   "aprt run: warning: watchdog refused a %d s timeout (%s); using its own\n",
                   config.supervisor.watchdog_timeout_s, std::strerror(errno));
    }
  }
  return r;
}

Runtime::~Runtime() {
  request_stop();
  join_threads();
  if (watchdog_fd_ >= 0) close(watchdog_fd_);
}

void Runtime::join_threads() {
  for (auto& c : cameras_) {
    if (c->started) pthread_join(c->thread, nullptr);
    c->started = false;
  }
  pthread_t* ts[2] = {&inference_, &publish_};
  for (int i = 0; i < 2; ++i) {
    if (threads_started_[i]) pthread_join(*ts[i], nullptr);
    threads_started_[i] = false;
  }
}

Status Runtime::start_thread(pthread_t* t, void* (*fn)(void*), void* arg, const ThreadConfig& tc,
                             const char* name) {
  pthread_attr_t attr;
  pthread_attr_init(&attr);
  if (tc.priority > 0) {
    sched_param sp{};
    sp.sched_priority = tc.priority;
    pthread_attr_setinheritsched(&attr, PTHREAD_EXPLICIT_SCHED);
    pthread_attr_setschedpolicy(&attr, SCHED_FIFO);
    pthread_attr_setschedparam(&attr, &sp);
  }
  int rc = pthread_create(t, &attr, fn, arg);
  if (rc == EPERM && tc.priority > 0) {
    std::fprintf(stderr,
                 "aprt run: warning: no permission for SCHED_FIFO priority %d on the %s thread "
                 "(needs CAP_SYS_NICE or an rtprio limit); running it with normal scheduling\n",
                 tc.priority, name);
    pthread_attr_setinheritsched(&attr, PTHREAD_INHERIT_SCHED);
    rc = pthread_create(t, &attr, fn, arg);
  }
  pthread_attr_destroy(&attr);
  if (rc != 0)
    return Error(Errc::kOutOfMemory, "run: cannot start the %s thread: %s", name,
                 std::strerror(rc));
  pthread_setname_np(*t, name);
  if (tc.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(tc.cpu, &set);
    if (pthread_setaffinity_np(*t, sizeof set, &set) != 0) {
      std::fprintf(stderr, "aprt run: warning: cannot pin the %s thread to CPU %d\n", name, tc.cpu);
    }
  }
  return ok();
}

void* Runtime::channel_main(void* channel) {
  Channel* c = static_cast<Channel*>(channel);
  c->owner->capture_loop(*c);
  return nullptr;
}
void* Runtime::inference_main(void* self) {
  static_cast<Runtime*>(self)->inference_loop();
  return nullptr;
}
void* Runtime::publish_main(void* self) {
  static_cast<Runtime*>(self)->publish_loop();
  return nullptr;
}

void Runtime::capture_loop(Channel& c) {
  const bool device = !c.replay();
  const bool primary = c.index == 0;  // deliberate camera stalls hit the trigger camera
  if (Status s = c.source->start(); !s) {
    std::fprintf(stderr, "aprt run: %s%s%s%s\n", cameras_.size() > 1 ? c.name.c_str() : "",
                 cameras_.size() > 1 ? ": " : "", s.error().message(),
                 device ? " (retrying with back-off)" : "");
    c.failed.store(true);
    if (!device) {  // a replay that cannot start will not start later
      c.done.store(true);
      return;
    }
  }
  while (!stop_.load(std::memory_order_acquire)) {
    c.beat.store(monotonic_ns(), std::memory_order_release);
    switch (c.source->next(&c.slot->back(), kWaitNs)) {
      case SourceResult::kFrame: {
        if (!c.source->driver_timestamps()) {
          c.slot->back().info.capture_ns = monotonic_ns();  // arrival, for frame age
        }
        c.slot->back().info.source = uint32_t(c.index);
        c.slot->publish();
        const uint64_t n = c.captured.fetch_add(1);
        if (const int64_t stall = primary ? faults_.stall_ns(n) : 0) {
          // The camera delivers nothing; the thread stays alive and keeps beating.
          const int64_t until = monotonic_ns() + stall;
          while (!stop_.load(std::memory_order_acquire) && monotonic_ns() < until) {
            const timespec ts{0, 5000000};
            nanosleep(&ts, nullptr);
            c.beat.store(monotonic_ns(), std::memory_order_release);
          }
        }
        if (c.failed.exchange(false, std::memory_order_acq_rel)) {
          std::fprintf(stderr, "aprt run: %s delivers frames again\n", c.source->name());
        }
        break;
      }
      case SourceResult::kTimeout: break;
      case SourceResult::kSkipped:
        frames_skipped_.fetch_add(1, std::memory_order_relaxed);
        std::fprintf(stderr, "aprt run: frame skipped: %s\n", c.source->error().message());
        break;
      case SourceResult::kEndOfStream: c.done.store(true, std::memory_order_release); return;
      case SourceResult::kFailed:
        if (!c.failed.exchange(true, std::memory_order_acq_rel)) {
          std::fprintf(stderr, "aprt run: %s\n", c.source->error().message());
        }
        break;
    }
  }
  c.done.store(true, std::memory_order_release);
}

const FrameBuffer* Runtime::take_frame(Channel& c, int64_t deadline_ns) noexcept {
  const FrameBuffer* f = nullptr;
  for (;;) {
    const uint32_t seen = c.slot->published();
    if (c.slot->take(&f)) break;
    const int64_t left = deadline_ns - monotonic_ns();
    if (left <= 0 || c.done.load(std::memory_order_acquire)) return nullptr;
    c.slot->wait(seen, std::min(left, kWaitNs));
  }
  if (c.replay()) c.source->note_taken(f->info.sequence + 1);
  return f;
}

namespace {

// Re-plans preprocessing when a frame's geometry or format changed (a camera
// renegotiated); false if the frame cannot be mapped to the model's input.
bool fit_plan(kernels::PreprocessPlan* plan, const FrameBuffer& f) {
  if (f.info.width == plan->width && f.info.height == plan->height &&
      f.info.format == plan->format) {
    return true;
  }
  return kernels::plan_preprocess(plan->params, f.info.format, f.info.width, f.info.height, plan);
}

}  // namespace

// A scan to the LiDAR model's input, the histogram's or the sampler's, with
// the geometry of the running model (a reloaded model keeps its input: the
// reload check, model_loader.cc, refuses another). @rt: bounded by the
// configured point count, no allocation.
uint32_t Runtime::scan_input(Engine& e, const FrameBuffer& f) {
  const size_t n = f.info.scan.points;
  kernels::LidarInputResult r;
  if (e.meta().modality == format::Modality::kLidarPoints) {
    r = kernels::lidar_points_input(points_input_, f.points(), n, e.kernel_set() != nullptr,
                                    scan_scratch_.data(), e.input().f32());
  } else {
    r = kernels::lidar_bev_input(bev_input_, f.points(), n, bev_counts_.data(), e.input().f32());
  }
  scan_points_.store(uint32_t(r.points), std::memory_order_relaxed);
  scan_dropped_.store(f.info.scan.non_finite + f.info.scan.over_capacity,
                      std::memory_order_relaxed);
  scan_clipped_.store(f.info.scan.clipped, std::memory_order_relaxed);
  if (!r.enough || r.points < size_t(config_.source.lidar.min_points)) {
    sparse_scans_.fetch_add(1, std::memory_order_relaxed);
    return kPoseSparseScan;
  }
  return 0;
}

void Runtime::inference_loop() {
  Engine* e = engine_.get();
  const int64_t stale_ns = int64_t(config_.supervisor.frame_timeout_ms * 1e6);
  const int64_t deadline_ns = int64_t(config_.supervisor.inference_deadline_ms * 1e6);
  const int64_t skew_ns = int64_t(config_.fusion.max_frame_skew_ms * 1e6);
  const size_t n_cams = cameras_.size();
  Channel& trigger = *cameras_[0];
  FusionParams fp;
  fp.max_position_spread_m = config_.fusion.max_position_spread_m;
  fp.max_orientation_spread_rad = config_.fusion.max_orientation_spread_deg * M_PI / 180.0;
  fp.min_agreeing = config_.fusion.min_agreeing;
  uint64_t index = 0;
  bool have_prev = false;
  double prev[3] = {};
  int64_t prev_ns = 0;
  while (!stop_.load(std::memory_order_acquire)) {
    inference_beat_.store(monotonic_ns(), std::memory_order_release);
    const FrameBuffer* f = nullptr;
    const uint32_t published = trigger.slot->published();
    if (!trigger.slot->take(&f)) {
      if (trigger.done.load(std::memory_order_acquire) && trigger.slot->published() == published) {
        if (!trigger.slot->take(&f)) break;  // nothing left
      } else {
        trigger.slot->wait(published, kWaitNs);
        continue;
      }
    }
    if (trigger.replay()) trigger.source->note_taken(f->info.sequence + 1);
    // A reloaded model takes over here, between two frames; the old one goes
    // back to the supervisor, which frees it (never this thread).
    if (Engine* next = pending_.exchange(nullptr, std::memory_order_acq_rel)) {
      retired_.store(e, std::memory_order_release);
      e = next;
    }
    const ModelMeta& m = e->meta();
    PoseRecord rec;
    rec.inference_start_ns = monotonic_ns();
    rec.capture_ns = f->info.capture_ns;
    rec.source_stamp_ns = f->info.source_stamp_ns;
    rec.frame_sequence = f->info.sequence;
    rec.source = f->info.source;
    uint32_t flags = 0;
    if (rec.inference_start_ns - f->info.capture_ns > stale_ns) flags |= kPoseStaleFrame;
    if (!trigger.scans && !fit_plan(trigger.plan.get(), *f)) {
      frames_skipped_.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    // The other cameras' frames of this cycle: each one's newest, waited for
    // up to the skew after the trigger frame was taken.
    const FrameBuffer* frames[kMaxFusedCameras] = {f};
    for (size_t i = 1; i < n_cams; ++i) {
      Channel& c = *cameras_[i];
      const FrameBuffer* g = take_frame(c, rec.inference_start_ns + skew_ns);
      if (g && std::llabs(g->info.capture_ns - f->info.capture_ns) > skew_ns) g = nullptr;
      if (g && !fit_plan(c.plan.get(), *g)) g = nullptr;
      if (!g) ++c.missing;
      frames[i] = g;
    }
    if (const int64_t hang = faults_.hang_ns(index)) {
      // A hung stage: no beat, so the supervisor must see it (FAULT, watchdog unpetted).
      const int64_t until = monotonic_ns() + hang;
      while (!stop_.load(std::memory_order_acquire) && monotonic_ns() < until) {
        const timespec ts{0, 5000000};
        nanosleep(&ts, nullptr);
      }
    }
    const float margin = float(config_.sanity.bounds_margin);
    CameraEstimate est[kMaxFusedCameras];
    for (size_t i = 0; i < n_cams; ++i) {
      if (!frames[i]) continue;
      if (cameras_[i]->scans) {
        flags |= scan_input(*e, *frames[i]);
      } else {
        kernels::preprocess_image(*cameras_[i]->plan, frames[i]->view(), e->input().f32());
      }
      (void)e->run();
      if (i == 0 && faults_.nan_output(index)) {
        e->output().f32()[0] = std::numeric_limits<float>::quiet_NaN();
      }
      const PoseEstimate p = decode_pose(e->output().f32(), m, margin);
      if (n_cams == 1) {
        rec.pose = p;
        break;
      }
      if (p.flags) ++cameras_[i]->flagged;
      est[i] = camera_to_base(p, cameras_[i]->base_from_sensor);
    }
    if (n_cams > 1) {
      const FusionResult fr = fuse_poses(est, int(n_cams), fp);
      // The outputs take the trigger camera's pose (its extrinsic brings it
      // back to this base_link, their map offset applies once).
      rec.pose = base_to_sensor(fr.position, fr.orientation, trigger.base_from_sensor);
      if (!fr.valid) {
        uint32_t camera_flags = 0;
        for (size_t i = 0; i < n_cams; ++i) camera_flags |= est[i].present ? est[i].flags : 0;
        rec.pose.flags = camera_flags;
        flags |= kPoseNoQuorum;
        ++fusion_no_quorum_;
      }
      FusionSummary& fs = rec.fusion;
      fs.cameras = uint8_t(n_cams);
      fs.present = uint8_t(fr.present);
      fs.usable = uint8_t(fr.usable);
      fs.inliers = uint8_t(fr.inliers);
      fs.inlier_mask = fr.inlier_mask;
      fs.spread_m = float(fr.spread_m);
      fs.spread_deg = float(fr.spread_deg);
      for (size_t i = 0; i < n_cams; ++i) {
        fs.deviation_m[i] = float(fr.deviation_m[i]);
        fs.deviation_deg[i] = float(fr.deviation_deg[i]);
        if (est[i].present && est[i].flags == 0 && !(fr.inlier_mask & (1u << i))) {
          ++cameras_[i]->outliers;
        }
      }
    }
    if (const int64_t overrun = faults_.overrun_ns(index)) {
      const timespec ts{time_t(overrun / 1000000000), long(overrun % 1000000000)};
      nanosleep(&ts, nullptr);
    }
    rec.inference_end_ns = monotonic_ns();
    if (save_index_ >= 0 && uint64_t(save_index_) == index) write_saved_frame(*f, rec, *e);
    flags |= rec.pose.flags;
    if (rec.inference_end_ns - rec.inference_start_ns > deadline_ns) {
      flags |= kPoseDeadlineMissed;
      deadline_misses_.fetch_add(1, std::memory_order_relaxed);
    }
    if (have_prev && config_.sanity.max_jump_m > 0 && !(flags & kPoseNonFinite)) {
      double d = 0;
      for (int k = 0; k < 3; ++k)
        d += (rec.pose.position[k] - prev[k]) * (rec.pose.position[k] - prev[k]);
      const double dt = double(rec.capture_ns - prev_ns) * 1e-9;
      if (std::sqrt(d) >
          config_.sanity.max_jump_m + config_.sanity.max_speed_mps * std::max(0.0, dt)) {
        flags |= kPoseJump;
      }
    }
    if (!(flags & (kPoseNonFinite | kPoseOutOfBounds | kPoseJump | kPoseNoQuorum))) {
      for (int k = 0; k < 3; ++k) prev[k] = rec.pose.position[k];
      prev_ns = rec.capture_ns;
      have_prev = true;
    }
    rec.flags = flags;
    rec.index = index++;
    rec.state = RunState(state_.load(std::memory_order_relaxed));
    rec.has_truth = f->info.has_truth;
    for (int k = 0; k < 3; ++k) rec.truth_position[k] = f->info.truth_position[k];
    for (int k = 0; k < 4; ++k) rec.truth_orientation[k] = f->info.truth_orientation[k];
    std::snprintf(rec.name, sizeof rec.name, "%s", f->info.name);
    last_frame_ns_.store(f->info.capture_ns, std::memory_order_release);
    last_flags_.store(flags, std::memory_order_release);
    poses_.fetch_add(1, std::memory_order_release);
    if (flags) poses_flagged_.fetch_add(1, std::memory_order_relaxed);
    if (!ring_->push(rec)) ring_full_.fetch_add(1, std::memory_order_relaxed);
  }
  inference_done_.store(true, std::memory_order_release);
}

void Runtime::print_pose(const PoseRecord& r) {
  char flags[96];
  pose_flags_text(r.flags & 0xff, flags, sizeof flags);
  if (r.flags & kPoseStaleFrame)
    std::strncat(flags, ",stale", sizeof flags - std::strlen(flags) - 1);
  if (r.flags & kPoseDeadlineMissed)
    std::strncat(flags, ",late", sizeof flags - std::strlen(flags) - 1);
  if (r.flags & kPoseJump) std::strncat(flags, ",jump", sizeof flags - std::strlen(flags) - 1);
  if (r.flags & kPoseNoQuorum)
    std::strncat(flags, ",no-quorum", sizeof flags - std::strlen(flags) - 1);
  if (r.flags & kPoseSparseScan)
    std::strncat(flags, ",sparse", sizeof flags - std::strlen(flags) - 1);
  if (r.fusion.cameras > 1) {  // agreeing / configured cameras
    char cams[24];
    std::snprintf(cams, sizeof cams, " cams %u/%u", unsigned(r.fusion.inliers),
                  unsigned(r.fusion.cameras));
    std::strncat(flags, cams, sizeof flags - std::strlen(flags) - 1);
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
        yaw_deg(r.pose.orientation), std::sqrt(d),
        angle_deg(r.pose.orientation, r.truth_orientation), ms, run_state_name(r.state), flags);
  } else {
    std::printf("%6llu %7.2fs  x %8.2f y %8.2f z %6.2f  yaw %7.1f  %5.1f ms  %-9s %s\n",
                static_cast<unsigned long long>(r.frame_sequence), t, p[0], p[1], p[2],
                yaw_deg(r.pose.orientation), ms, run_state_name(r.state), flags);
  }
}

void Runtime::publish_loop() {
  PoseRecord r;
  const int64_t status_period = int64_t(1e9 / config_.output.status_rate_hz);
  int64_t next_status = monotonic_ns();
  double last_inference_ms = 0;
  FusionSummary last_fusion;
  for (;;) {
    publish_beat_.store(monotonic_ns(), std::memory_order_release);
    if (monotonic_ns() >= next_status) {
      next_status += status_period;
      StatusSnapshot st;
      st.state = RunState(state_.load(std::memory_order_relaxed));
      st.reason = reason_.load(std::memory_order_acquire);
      st.poses = poses_.load(std::memory_order_relaxed);
      st.flagged = poses_flagged_.load(std::memory_order_relaxed);
      st.deadline_misses = deadline_misses_.load(std::memory_order_relaxed);
      st.frames_skipped = frames_skipped_.load(std::memory_order_relaxed);
      st.last_flags = last_flags_.load(std::memory_order_relaxed);
      st.last_inference_ms = last_inference_ms;
      st.fusion = &last_fusion;
      if (cameras_[0]->scans) {
        st.lidar = true;
        st.scan_points = scan_points_.load(std::memory_order_relaxed);
        st.scan_dropped = scan_dropped_.load(std::memory_order_relaxed);
        st.scan_clipped = scan_clipped_.load(std::memory_order_relaxed);
        st.sparse_scans = sparse_scans_.load(std::memory_order_relaxed);
      }
      outputs_->publish_status(st, realtime_ns());
    }
    if (!ring_->pop(&r)) {
      if (inference_done_.load(std::memory_order_acquire) && ring_->size() == 0) break;
      if (stop_.load(std::memory_order_acquire) && ring_->size() == 0) break;
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
      outputs_->publish(r, now, realtime_ns() - now);
    }
    output_errors_.store(outputs_->stats().dds_errors + injected_publish_failures_,
                         std::memory_order_release);
    last_inference_ms = double(r.inference_end_ns - r.inference_start_ns) * 1e-6;
    last_fusion = r.fusion;
    if (timing_count_ < timings_.size()) {
      timings_[timing_count_++] = {r.capture_ns, r.inference_start_ns, r.inference_end_ns, now};
    }
    published_.fetch_add(1, std::memory_order_release);
    if (r.has_truth && error_count_ < pos_errors_.size()) {
      double d = 0;
      for (int k = 0; k < 3; ++k) {
        d +=
            (r.pose.position[k] - r.truth_position[k]) * (r.pose.position[k] - r.truth_position[k]);
      }
      pos_errors_[error_count_] = float(std::sqrt(d));
      rot_errors_[error_count_++] = float(angle_deg(r.pose.orientation, r.truth_orientation));
    }
  }
}

void Runtime::print_summary() {
  std::vector<double> infer, e2e;
  for (size_t i = 0; i < timing_count_; ++i) {
    infer.push_back(double(timings_[i].inference_end_ns - timings_[i].inference_start_ns) * 1e-6);
    e2e.push_back(double(timings_[i].publish_ns - timings_[i].capture_ns) * 1e-6);
  }
  std::printf(
      "\nsummary: %llu frames captured, %llu skipped, %llu dropped as stale by the slot; "
      "%llu poses (%llu flagged), %llu deadline misses\n",
      static_cast<unsigned long long>(stats_.frames_captured),
      static_cast<unsigned long long>(stats_.frames_skipped),
      static_cast<unsigned long long>(stats_.frames_dropped),
      static_cast<unsigned long long>(stats_.poses),
      static_cast<unsigned long long>(stats_.poses_flagged),
      static_cast<unsigned long long>(stats_.deadline_misses));
  if (!infer.empty()) {
    std::printf(
        "latency: inference median %.1f ms p99 %.1f ms max %.1f ms; capture to publish "
        "median %.1f ms p99 %.1f ms max %.1f ms (%s kernels, %d threads)\n",
        percentile(infer, 0.5), percentile(infer, 0.99), percentile(infer, 1.0),
        percentile(e2e, 0.5), percentile(e2e, 0.99), percentile(e2e, 1.0), engine_->isa(),
        engine_->threads());
  }
  if (cameras_[0]->scans) {
    std::printf("lidar: %llu of %llu scans too sparse for the model (flagged)\n",
                static_cast<unsigned long long>(stats_.sparse_scans),
                static_cast<unsigned long long>(stats_.poses));
  }
  if (cameras_.size() > 1) {
    std::printf("fusion: %zu cameras; %llu of %llu cycles without a quorum\n", cameras_.size(),
                static_cast<unsigned long long>(stats_.fusion_no_quorum),
                static_cast<unsigned long long>(stats_.poses));
    for (size_t i = 0; i < cameras_.size(); ++i) {
      const RunStats::Camera& c = stats_.cameras[i];
      std::printf(
          "  camera %s: %llu frames, %llu dropped as stale, %llu cycles without a frame in time, "
          "%llu estimates flagged, %llu rejected as outliers\n",
          cameras_[i]->name.c_str(), static_cast<unsigned long long>(c.frames),
          static_cast<unsigned long long>(c.dropped), static_cast<unsigned long long>(c.missing),
          static_cast<unsigned long long>(c.flagged), static_cast<unsigned long long>(c.outliers));
    }
  }
  pos_errors_.resize(error_count_);  // after the run: the summary may allocate
  rot_errors_.resize(error_count_);
  if (!pos_errors_.empty()) {
    double ps = 0, rs = 0;
    for (float v : pos_errors_) ps += v;
    for (float v : rot_errors_) rs += v;
    std::printf(
        "errors against ground truth: position median %.2f m, mean %.2f m, p90 %.2f m; "
        "orientation median %.2f deg, mean %.2f deg, p90 %.2f deg\n",
        percentile(pos_errors_, 0.5), ps / double(pos_errors_.size()), percentile(pos_errors_, 0.9),
        percentile(rot_errors_, 0.5), rs / double(rot_errors_.size()),
        percentile(rot_errors_, 0.9));
  }
}

int Runtime::run() {
  if (config_.threads.lock_memory && mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    std::fprintf(stderr, "aprt run: warning: mlockall failed (%s); memory may be paged\n",
                 std::strerror(errno));
  }
  started_ns_ = monotonic_ns();
  inference_beat_ = publish_beat_ = started_ns_;
  for (auto& c : cameras_) c->beat = started_ns_;
  Status s;
  if (!(s = start_thread(&publish_, publish_main, this, config_.threads.publish, "aprt-publish")) ||
      !(threads_started_[1] = true) ||
      !(s = start_thread(&inference_, inference_main, this, config_.threads.inference,
                         "aprt-infer")) ||
      !(threads_started_[0] = true)) {
    std::fprintf(stderr, "aprt run: %s\n", s.error().message());
    request_stop();
    return 1;
  }
  for (auto& c : cameras_) {
    if (!(s = start_thread(&c->thread, channel_main, c.get(), config_.threads.capture,
                           c->thread_name.c_str()))) {
      std::fprintf(stderr, "aprt run: %s\n", s.error().message());
      request_stop();
      return 1;
    }
    c->started = true;
  }
  if (config_.supervisor.systemd) sd_notify_text("READY=1\nSTATUS=STARTING");
  const int64_t period = int64_t(1e9 / config_.supervisor.rate_hz);
  RunState last = RunState::kStarting;
  int code = 0;
  int64_t next = monotonic_ns();
  while (!stop_.load(std::memory_order_acquire)) {
    next += period;
    const timespec ts{time_t(next / 1000000000), long(next % 1000000000)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
    Health h;
    h.now_ns = monotonic_ns();
    h.started_ns = started_ns_;
    h.last_frame_ns = last_frame_ns_.load(std::memory_order_acquire);
    // The trigger camera's end ends the run; a stalled capture thread of any
    // camera is a stalled stage; any camera failing is a failing source.
    const bool capture_done = cameras_[0]->done.load(std::memory_order_acquire);
    const bool inference_done = inference_done_.load(std::memory_order_acquire);
    h.capture_beat_ns = h.now_ns;
    h.source_failed = false;
    for (const auto& c : cameras_) {
      if (!c->done.load(std::memory_order_acquire)) {
        h.capture_beat_ns = std::min(h.capture_beat_ns, c->beat.load(std::memory_order_acquire));
      }
      h.source_failed = h.source_failed || c->failed.load(std::memory_order_acquire);
    }
    h.inference_beat_ns =
        inference_done ? h.now_ns : inference_beat_.load(std::memory_order_acquire);
    h.publish_beat_ns = publish_beat_.load(std::memory_order_acquire);
    h.poses = poses_.load(std::memory_order_acquire);
    h.last_flags = last_flags_.load(std::memory_order_acquire);
    h.output_errors = output_errors_.load(std::memory_order_acquire);
    h.end_of_stream = capture_done && inference_done && ring_->size() == 0;
    if (capture_done && h.last_frame_ns)
      h.last_frame_ns = h.now_ns;  // a finished replay is not stale
    if (!warm_.valid) {
      const uint64_t n = published_.load(std::memory_order_acquire);
      if (!steady_.valid && n > 0) {
        steady_ = {true, allocation_count_ ? allocation_count_() : 0, current_rss_kb()};
      }
      if (n >= kRssWarmupPoses) {
        warm_ = {true, allocation_count_ ? allocation_count_() : 0, current_rss_kb()};
      }
    }
    service_reload();
    const RunState st = supervisor_.step(h);
    state_.store(uint8_t(st), std::memory_order_relaxed);
    reason_.store(supervisor_.reason(), std::memory_order_release);
    if (st != last) {
      if (state_change_count_ < kMaxStateChanges) {
        state_changes_[state_change_count_++] = {st, supervisor_.reason(), h.now_ns};
      }
      char msg[192];
      std::snprintf(msg, sizeof msg, "STATUS=%s: %s", run_state_name(st), supervisor_.reason());
      if (config_.supervisor.systemd) sd_notify_text(msg);
      if (st != RunState::kRunning || last != RunState::kStarting) {
        std::fprintf(stderr, "aprt run: state %s (%s)\n", run_state_name(st), supervisor_.reason());
      }
      last = st;
    }
    if (st != RunState::kFault && supervisor_.stages_alive(h)) {
      if (watchdog_fd_ >= 0) ioctl(watchdog_fd_, WDIOC_KEEPALIVE, 0);
      if (config_.supervisor.systemd) sd_notify_text("WATCHDOG=1");
    }
    if (st == RunState::kStopping) break;
    if (st == RunState::kFault) {
      code = 3;
      break;
    }
  }
  request_stop();
  join_threads();
  end_ = {true, allocation_count_ ? allocation_count_() : 0, current_rss_kb()};
  // A reload the inference thread did not reach, or reached after the last tick.
  service_reload();
  if (pending_.exchange(nullptr)) spare_.reset();
  duration_s_ = double(monotonic_ns() - started_ns_) * 1e-9;
  if (config_.supervisor.systemd) sd_notify_text("STOPPING=1");
  if (watchdog_fd_ >= 0 && code == 0) {
    if (write(watchdog_fd_, "V", 1) != 1) {  // magic close: a clean stop does not reset the ECU
      std::fprintf(stderr, "aprt run: warning: watchdog magic close failed\n");
    }
  }
  stats_.frames_captured = cameras_[0]->captured.load();
  stats_.frames_skipped = frames_skipped_.load();
  stats_.frames_dropped = cameras_[0]->slot->dropped();
  stats_.fusion_no_quorum = fusion_no_quorum_;
  stats_.sparse_scans = sparse_scans_.load();
  stats_.cameras.clear();
  for (const auto& c : cameras_) {
    stats_.cameras.push_back(
        {c->captured.load(), c->missing, c->flagged, c->outliers, c->slot->dropped()});
  }
  stats_.poses = poses_.load();
  stats_.poses_flagged = poses_flagged_.load();
  stats_.deadline_misses = deadline_misses_.load();
  stats_.ring_full = ring_full_.load();
  stats_.reloads = reloads_;
  stats_.publish_failures_injected = injected_publish_failures_;
  stats_.reloads_refused = reloads_refused_;
  if (config_.output.summary) {
    print_summary();
    outputs_->print_summary();
  }
  return code;
}

void Runtime::write_saved_frame(const FrameBuffer& f, const PoseRecord& rec, const Engine& e) {
  FILE* raw = std::fopen(save_path_.c_str(), "wb");
  FILE* txt = std::fopen((save_path_ + ".txt").c_str(), "w");
  bool ok = raw && txt && std::fwrite(f.data, 1, f.info.bytes, raw) == f.info.bytes;
  if (txt) {
    const PoseEstimate& p = rec.pose;
    ok = std::fprintf(txt,
                      "format %s\nwidth %d\nheight %d\nstride %zu\nbytes %zu\nname %s\n"
                      "model %s\nisa %s\npose %.9g %.9g %.9g %.9g %.9g %.9g %.9g\nflags %u\n",
                      pixel_format_name(f.info.format), f.info.width, f.info.height, f.info.stride,
                      f.info.bytes, f.info.name, config_.model.c_str(), e.isa(), p.position[0],
                      p.position[1], p.position[2], p.orientation[0], p.orientation[1],
                      p.orientation[2], p.orientation[3], p.flags) > 0 &&
         ok;
  }
  if (raw) ok = std::fclose(raw) == 0 && ok;
  if (txt) ok = std::fclose(txt) == 0 && ok;
  std::fprintf(stderr, "aprt run: %s frame %s to %s\n", ok ? "saved" : "could not save",
               f.info.name, save_path_.c_str());
}

void Runtime::service_reload() {
  if (retired_.exchange(nullptr, std::memory_order_acq_rel)) {
    engine_.swap(spare_);  // engine_: the model now running; spare_: the old one
    spare_.reset();
    ++reloads_;
    std::fprintf(stderr, "aprt run: model reloaded: %s (%s kernels); reload %llu\n",
                 config_.model.c_str(), engine_->isa(), static_cast<unsigned long long>(reloads_));
  }
  if (!reload_requested_.exchange(false, std::memory_order_acq_rel)) return;
  if (spare_) {
    std::fprintf(stderr, "aprt run: reload requested while one is switching; ignored\n");
    return;
  }
  std::string note;
  auto next = load_model(config_, &note);
  Status fits = next ? reload_compatible(engine_->meta(), next.value()->meta()) : ok();
  if (!next || !fits) {
    ++reloads_refused_;
    std::fprintf(stderr, "aprt run: reload refused, the running model stays: %s\n",
                 next ? fits.error().message() : next.error().message());
    return;
  }
  if (!note.empty())
    std::fprintf(stderr, "aprt run: %s: %s\n", config_.model.c_str(), note.c_str());
  spare_ = std::move(next.value());
  pending_.store(spare_.get(), std::memory_order_release);
}

Status Runtime::write_timing_report(const char* json_path) const {
  TimingContext ctx;
  ctx.model = config_.model.c_str();
  const bool replay = config_.source.type == "replay" || config_.source.type == "lidar_replay";
  const Config::Source& src = config_.source;
  ctx.source =
      replay                      ? src.replay.path.c_str()
      : src.type == "pointcloud2" ? src.pointcloud2.topic.c_str()
      : src.type == "libcamera"
          ? (src.libcamera.camera.empty() ? "libcamera camera 0" : src.libcamera.camera.c_str())
          : src.v4l2.device.c_str();
  ctx.isa = engine_->isa();
  ctx.threads = engine_->threads();
  const double hz = replay                      ? (src.replay.recorded ? 0 : src.replay.rate_hz)
                    : src.type == "pointcloud2" ? 0.0  // the LiDAR's own rate
                    : src.type == "libcamera"   ? double(src.libcamera.fps)
                                                : double(src.v4l2.fps);
  ctx.camera_period_ms = hz > 0 ? 1000.0 / hz : 0;
  ctx.inference_deadline_ms = config_.supervisor.inference_deadline_ms;
  ctx.allocations_counted = allocation_count_ != nullptr;
  ctx.counter_covers_malloc = counter_covers_malloc_;
  ctx.steady = steady_;
  ctx.warm = warm_;
  ctx.warmup_poses = kRssWarmupPoses;
  ctx.end = end_;
  // getrusage's peak is updated lazily by the kernel; never below what statm saw.
  ctx.peak_rss_kb = std::max(peak_rss_kb(), end_.rss_kb);
  ctx.duration_s = duration_s_;
  return aprt::write_timing_report(json_path, timings_.data(), timing_count_, stats_, ctx);
}

}  // namespace aprt
