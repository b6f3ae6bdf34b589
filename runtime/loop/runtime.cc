#include "runtime/loop/runtime.h"

#include <pthread.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "drivers/codec/frame_sidecar.h"
#include "runtime/loop/model_loader.h"
#include "runtime/loop/process_memory.h"
#include "runtime/loop/rt_thread.h"
#include "runtime/loop/run_report.h"

namespace aprt {

Expected<std::unique_ptr<Runtime>> Runtime::create(const Config& config, const Config* companion) {
  std::unique_ptr<Runtime> r(new (std::nothrow) Runtime());
  if (!r) return Error(Errc::kOutOfMemory, "run: out of memory");
  r->config_ = config;
  const Config& c = r->config_;
  // Before the engine's workers and the DDS library's threads start.
  bound_process_memory(c.threads);
  std::string note;
  auto engine = load_model(model_request(c), &note);
  if (!engine) return engine.error();
  if (!note.empty()) std::fprintf(stderr, "aprt run: %s: %s\n", c.model.c_str(), note.c_str());
  r->models_.reset(new (std::nothrow) ModelSlot(c, std::move(engine.value())));
  if (!r->models_) return Error(Errc::kOutOfMemory, "run: out of memory");
  if (Status s = r->faults_.configure(c.fault_injection); !s) return s.error();
  if (r->faults_.any()) {
    std::fprintf(stderr, "aprt run: %zu deliberate fault(s) configured (fault_injection)\n",
                 c.fault_injection.size());
  }

  const std::vector<Config::Camera> cams = camera_list(c);
  if (cams.size() > size_t(kMaxFusedCameras)) {
    return Error(Errc::kInvalidArgument, "run: at most %d cameras", kMaxFusedCameras);
  }
  size_t frames = 0;  // the first replay's length
  for (size_t i = 0; i < cams.size(); ++i) {
    size_t n = 0;
    auto ch = open_channel(cams[i], i, cams.size(), r->models_->running(), c.model, &n);
    if (!ch) return ch.error();
    if (i == 0) frames = n;
    r->channel_ptrs_.push_back(ch.value().get());
    r->channels_.push_back(std::move(ch.value()));
  }
  if (c.sanity.filter.enabled && c.odometry.source != "replay") {
    auto od = OdometryInput::create(c.odometry);
    if (!od) return Error(od.error().code(), "run: %s", od.error().message());
    r->odometry_ = std::move(od.value());
  } else if (c.sanity.filter.enabled && !r->channels_[0]->source->has_odometry()) {
    return Error(Errc::kInvalidArgument,
                 "run: sanity.filter needs the vehicle's odometry, and %s has no odometry.txt "
                 "(python3 -m aprt_tools odometry FOLDER writes one for a synthetic drive)",
                 c.source.replay.path.c_str());
  }
  r->estimator_.reset(new (std::nothrow) Estimator(
      c, r->models_->running().meta(), r->channel_ptrs_.data(), r->channel_ptrs_.size()));
  if (r->odometry_) r->estimator_->use_odometry(r->odometry_.get());
  if (companion) {
    auto co = Companion::create(*companion, c.fusion.companion_max_age_ms);
    if (!co) return co.error();
    r->companion_ = std::move(co.value());
    r->sensor_fusion_.max_position_spread_m = c.fusion.max_position_spread_m;
    r->sensor_fusion_.max_yaw_spread_rad = c.fusion.max_orientation_spread_deg * M_PI / 180.0;
    r->sensor_fusion_.min_lead_s = c.fusion.min_lead_s;
    r->sensor_fusion_.cross_check = c.fusion.cross_check;
    fallback_sigma(c, r->models_->running().meta(), &r->own_sigma_pos_m_, &r->own_sigma_rot_rad_);
  }
  auto outputs = PoseOutputs::create(c, r->models_->running().meta());
  if (!outputs) return outputs.error();
  r->outputs_ = std::move(outputs.value());
  r->ring_.reset(new (std::nothrow) PoseRing());
  // Per-pose records for the summary and --timing: the run's length when it is
  // known, else output.records (later poses are not recorded). Once 2^20
  // here: 48 MiB, every page written and, with lock_memory, locked.
  const bool replay = c.source.replay_source();
  const size_t capacity = replay && c.source.replay.frames > 0 ? size_t(c.source.replay.frames) + 16
                          : replay && !c.source.replay.loop    ? frames + 16
                                                               : size_t(c.output.records);
  r->publisher_.reset(new (std::nothrow) Publisher(c, *r->ring_, *r->outputs_, r->shared_,
                                                   r->faults_, r->channels_[0]->scans(), capacity));
  if (!r->estimator_ || !r->ring_ || !r->publisher_) {
    return Error(Errc::kOutOfMemory, "run: out of memory");
  }
  auto supervision = Supervision::create(c);
  if (!supervision) return supervision.error();
  r->supervision_ = std::move(supervision.value());
  return r;
}

Runtime::~Runtime() {
  request_stop();
  if (const char* stuck = join_threads_by(monotonic_ns() + kStopBoundNs)) {
    exit_stuck(stuck, kFaultExitCode);
  }
}

const char* Runtime::join_threads_by(int64_t deadline_ns) {
  auto join = [&](pthread_t t) { return join_thread_by(t, deadline_ns) ? 0 : 1; };
  for (auto& c : channels_) {
    if (c->started && join(c->thread) != 0) return c->thread_name.c_str();
    c->started = false;
  }
  if (companion_ && companion_->channel().started) {
    if (join(companion_->channel().thread) != 0) return "aprt-companion";
    companion_->channel().started = false;
  }
  if (inference_started_ && join(inference_) != 0) return "aprt-infer";
  inference_started_ = false;
  if (publish_started_ && join(publish_) != 0) return "aprt-publish";
  publish_started_ = false;
  if (models_ && !models_->stop_loader(deadline_ns)) return "aprt-reload";
  return nullptr;
}

void Runtime::exit_stuck(const char* stage, int code) {
  // Nothing a stuck thread may still touch is read or freed: the counters are
  // atomics; the summary, the outputs and the engine are left as they are.
  std::fprintf(stderr,
               "aprt run: state FAULT (stage %s did not stop within %.1f s: blocked in a system "
               "call?); exiting without it\n",
               stage, double(kStopBoundNs) * 1e-9);
  std::fprintf(stderr, "aprt run: %llu poses (%llu flagged) before the stop\n",
               static_cast<unsigned long long>(shared_.poses.load()),
               static_cast<unsigned long long>(shared_.poses_flagged.load()));
  if (config_.supervisor.systemd) {
    char msg[160];
    std::snprintf(msg, sizeof msg, "STATUS=FAULT: stage %s stuck at stop\nSTOPPING=1", stage);
    sd_notify_text(msg);
  }
  std::fflush(stdout);
  std::fflush(stderr);
  // No watchdog magic close: a supervised ECU resets.
  _exit(code == 0 ? kFaultExitCode : code);
}

void* Runtime::inference_main(void* self) {
  static_cast<Runtime*>(self)->inference_loop();
  return nullptr;
}

void* Runtime::publish_main(void* self) {
  static_cast<Runtime*>(self)->publisher_->run();
  return nullptr;
}

void Runtime::inference_loop() {
  Engine* e = models_->first();
  const int64_t skew_ns = int64_t(config_.fusion.max_frame_skew_ms * 1e6);
  const size_t n_cams = channels_.size();
  CaptureChannel& trigger = *channels_[0];
  Estimator& est = *estimator_;
  uint64_t index = 0;
  while (!shared_.stop.load(std::memory_order_acquire)) {
    shared_.inference_beat.store(monotonic_ns(), std::memory_order_release);
    const FrameBuffer* f = nullptr;
    const uint32_t published = trigger.slot->published();
    if (!trigger.slot->take(&f)) {
      if (trigger.done.load(std::memory_order_acquire) && trigger.slot->published() == published) {
        if (!trigger.slot->take(&f)) break;  // nothing left
      } else {
        trigger.slot->wait(published, kLoopWaitNs);
        continue;
      }
    }
    if (trigger.replay()) trigger.source->note_taken(f->info.sequence + 1);
    // A reloaded model takes over here, between two frames; the old one goes
    // back to the supervisor, which frees it (never this thread).
    if (Engine* next = models_->take_pending()) {
      models_->retire(e);
      e = next;
    }
    PoseRecord rec;
    uint32_t flags = est.start(*f, &rec);
    if (!est.fits(0, *f)) {
      shared_.frames_skipped.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    // The other cameras' frames of this cycle: each one's newest, waited for
    // up to the skew after the trigger frame was taken.
    const FrameBuffer* frames[kMaxFusedCameras] = {f};
    for (size_t i = 1; i < n_cams; ++i) {
      CaptureChannel& c = *channels_[i];
      const FrameBuffer* g = take_frame(c, rec.inference_start_ns + skew_ns);
      if (g && std::llabs(g->info.capture_ns - f->info.capture_ns) > skew_ns) g = nullptr;
      if (g && !est.fits(i, *g)) g = nullptr;
      if (!g) ++c.missing;
      frames[i] = g;
    }
    if (const int64_t hang = faults_.hang_ns(index)) {
      // A hung stage as a real one hangs: blocked in the kernel, deaf to the
      // stop flag (FaultInjector::block). The supervisor must see it (FAULT,
      // watchdog unpetted) and end the process without this thread.
      FaultInjector::block(hang);
    }
    flags |= est.infer(*e, frames, faults_.nan_output(index), &rec);
    if (trigger.scans()) {
      const ScanNote& sn = est.last_scan();
      shared_.scan_points.store(sn.points, std::memory_order_relaxed);
      shared_.scan_dropped.store(sn.dropped, std::memory_order_relaxed);
      shared_.scan_clipped.store(sn.clipped, std::memory_order_relaxed);
      shared_.sparse_scans.store(est.sparse_scans(), std::memory_order_relaxed);
    }
    if (const int64_t overrun = faults_.overrun_ns(index)) {
      const timespec ts{time_t(overrun / 1000000000), long(overrun % 1000000000)};
      nanosleep(&ts, nullptr);
    }
    rec.inference_end_ns = monotonic_ns();
    if (save_index_ >= 0 && uint64_t(save_index_) == index) write_saved_frame(*f, rec, *e);
    flags = est.check(&rec, flags);
    if (companion_) flags = fuse_companion(&rec, flags);
    shared_.deadline_misses.store(est.deadline_misses(), std::memory_order_relaxed);
    rec.flags = flags;
    rec.index = index++;
    rec.state = shared_.run_state();
    rec.has_truth = f->info.has_truth;
    for (int k = 0; k < 3; ++k) rec.truth_position[k] = f->info.truth_position[k];
    for (int k = 0; k < 4; ++k) rec.truth_orientation[k] = f->info.truth_orientation[k];
    std::snprintf(rec.name, sizeof rec.name, "%s", f->info.name);
    shared_.last_frame_ns.store(f->info.capture_ns, std::memory_order_release);
    shared_.last_flags.store(flags, std::memory_order_release);
    shared_.poses.fetch_add(1, std::memory_order_release);
    if (flags) shared_.poses_flagged.fetch_add(1, std::memory_order_relaxed);
    if (!ring_->push(rec)) shared_.ring_full.fetch_add(1, std::memory_order_relaxed);
  }
  shared_.inference_done.store(true, std::memory_order_release);
}

uint32_t Runtime::fuse_companion(PoseRecord* rec, uint32_t flags) noexcept {
  Companion& co = *companion_;
  co.poll();
  SensorEstimate own = sensor_estimate(*rec, flags, own_sigma_pos_m_, own_sigma_rot_rad_);
  own.valid_for_s = own_streak_.update(own.flags == 0, estimator_->last_gate_s());
  const SensorEstimate other = co.at(rec->capture_ns);
  const SensorFusionResult r = fuse_sensors(own, other, sensor_fusion_);
  CompanionNote& n = rec->companion;
  n.configured = true;
  n.present = other.present;
  n.from = uint8_t(r.from);
  n.disagree = r.disagree;
  n.flags = other.flags;
  n.distance_m = float(r.distance_m);
  n.yaw_diff_deg = r.yaw_diff_rad < 0 ? -1.0f : float(r.yaw_diff_rad * 180.0 / M_PI);
  Companion::Stats& st = co.stats();
  if (other.present) {
    const double age_ms = double(rec->capture_ns - co.latest_capture_ns()) * 1e-6;
    n.age_ms = float(age_ms);
    st.age_sum_ms += age_ms;
    st.age_max_ms = std::max(st.age_max_ms, age_ms);
  }
  if (r.pose.flags == 0) ++st.used[size_t(r.from) & 3];
  if (r.disagree) ++st.disagreements;
  if (!other.present) ++st.stale;
  // The run's own estimate going out (valid or shown flagged) stays exactly as it was.
  if (r.from == FusedFrom::kPrimary) return r.pose.flags;
  write_fused(r.pose, channels_[0]->base_from_sensor, rec);
  return r.pose.flags;
}

// What the supervisor sees at one tick.
Health Runtime::health(int64_t now_ns) const {
  Health h;
  h.now_ns = now_ns;
  h.started_ns = started_ns_;
  h.last_frame_ns = shared_.last_frame_ns.load(std::memory_order_acquire);
  // The trigger camera's end ends the run; a stalled capture thread of any
  // camera is a stalled stage; any camera failing is a failing source.
  const bool capture_done = channels_[0]->done.load(std::memory_order_acquire);
  const bool inference_done = shared_.inference_done.load(std::memory_order_acquire);
  h.capture_beat_ns = h.now_ns;
  h.source_failed = false;
  const auto watch = [&](const CaptureChannel& c) {
    if (!c.done.load(std::memory_order_acquire)) {
      h.capture_beat_ns = std::min(h.capture_beat_ns, c.beat.load(std::memory_order_acquire));
    }
    h.source_failed = h.source_failed || c.failed.load(std::memory_order_acquire);
  };
  for (const auto& c : channels_) watch(*c);
  // A companion that stalls or fails degrades the run like a camera would;
  // its end (a shorter replay) ends nothing.
  if (companion_) watch(companion_->channel());
  h.inference_beat_ns =
      inference_done ? h.now_ns : shared_.inference_beat.load(std::memory_order_acquire);
  h.publish_beat_ns = shared_.publish_beat.load(std::memory_order_acquire);
  h.poses = shared_.poses.load(std::memory_order_acquire);
  h.last_flags = shared_.last_flags.load(std::memory_order_acquire);
  h.output_errors = shared_.output_errors.load(std::memory_order_acquire);
  h.end_of_stream = capture_done && inference_done && ring_->size() == 0;
  h.frame_limit = channels_[0]->frame_limit != 0;
  if (capture_done && h.last_frame_ns)
    h.last_frame_ns = h.now_ns;  // a finished replay is not stale
  return h;
}

void Runtime::measure_budget() {
  const Engine& e = models_->running();
  budget_valid_ = measure_memory(e.memory_block(), e.memory().total_bytes,
                                 thread_stack_bytes(config_.threads), &budget_);
}

void Runtime::sample_memory() {
  const uint64_t n = shared_.published.load(std::memory_order_acquire);
  if (!budget_valid_ && n >= kBudgetPoses) measure_budget();
  if (warm_.valid) return;
  if (!steady_.valid && n > 0) {
    steady_ = {true, allocation_count_ ? allocation_count_() : 0, current_rss_kb()};
  }
  if (n >= kRssWarmupPoses) {
    warm_ = {true, allocation_count_ ? allocation_count_() : 0, current_rss_kb()};
  }
}

int Runtime::run() {
  if (config_.threads.lock_memory && mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    std::fprintf(stderr, "aprt run: warning: mlockall failed (%s); memory may be paged\n",
                 std::strerror(errno));
  }
  // From here a broken invariant in any thread is a FAULT (exit code 3).
  const FatalHandler previous = install_fault_handler(config_.supervisor.systemd);
  started_ns_ = monotonic_ns();
  shared_.inference_beat = shared_.publish_beat = started_ns_;
  for (auto& c : channels_) c->beat = started_ns_;
  if (companion_) companion_->channel().beat = started_ns_;
  publisher_->set_started(started_ns_);
  const size_t stack = thread_stack_bytes(config_.threads);
  Status s;
  if (!(s = start_thread(&publish_, publish_main, this, config_.threads.publish, "aprt-publish",
                         stack)) ||
      !(publish_started_ = true) ||
      !(s = start_thread(&inference_, inference_main, this, config_.threads.inference, "aprt-infer",
                         stack)) ||
      !(inference_started_ = true)) {
    std::fprintf(stderr, "aprt run: %s\n", s.error().message());
    request_stop();
    set_fatal_handler(previous);
    return 1;
  }
  // Each camera's capture thread, then the companion's (which injects no faults).
  const auto start_capture = [&](CaptureChannel& c, size_t run_channels,
                                 const FaultInjector* faults) {
    c.run_channels = run_channels;
    c.shared = &shared_;
    c.faults = faults;
    if (!(s = start_thread(&c.thread, capture_thread, &c, config_.threads.capture,
                           c.thread_name.c_str(), stack))) {
      std::fprintf(stderr, "aprt run: %s\n", s.error().message());
      request_stop();
      set_fatal_handler(previous);
      return false;
    }
    c.started = true;
    return true;
  };
  for (auto& c : channels_) {
    if (!start_capture(*c, channels_.size(), &faults_)) return 1;
  }
  // The run has one channel more; the companion's messages carry its name.
  if (companion_ && !start_capture(companion_->channel(), channels_.size() + 1, &no_faults_)) {
    return 1;
  }
  if (!(s = models_->start_loader())) {
    std::fprintf(stderr, "aprt run: %s\n", s.error().message());
    request_stop();
    set_fatal_handler(previous);
    return 1;
  }
  supervision_->ready();
  const int64_t period = int64_t(1e9 / config_.supervisor.rate_hz);
  int code = 0;
  int64_t next = monotonic_ns();
  while (!shared_.stop.load(std::memory_order_acquire)) {
    next += period;
    const timespec ts{time_t(next / 1000000000), long(next % 1000000000)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
    const Health h = health(monotonic_ns());
    sample_memory();
    models_->service();
    const RunState st = supervision_->tick(h, shared_);
    if (st == RunState::kStopping) break;
    if (st == RunState::kFault) {
      code = kFaultExitCode;
      break;
    }
  }
  request_stop();
  if (const char* stuck = join_threads_by(monotonic_ns() + kStopBoundNs)) exit_stuck(stuck, code);
  set_fatal_handler(previous);
  publisher_->print_state_lines();  // the last change (STOPPING, FAULT) after the last pose
  end_ = {true, allocation_count_ ? allocation_count_() : 0, current_rss_kb()};
  if (!budget_valid_) measure_budget();  // a run shorter than a second
  models_->finish();
  duration_s_ = double(monotonic_ns() - started_ns_) * 1e-9;
  supervision_->stopping(code == 0);
  collect_stats();
  if (config_.output.summary) {
    RunSummary sum;
    sum.stats = &stats_;
    sum.timings = publisher_->timings(&sum.timing_count);
    sum.error_count = publisher_->errors(&sum.position_errors, &sum.orientation_errors);
    sum.isa = models_->running().isa();
    sum.threads = models_->running().threads();
    sum.lidar = channels_[0]->scans();
    for (const auto& c : channels_) sum.camera_names.push_back(c->name);
    char memory[200] = "";
    if (budget_valid_) memory_budget_text(budget_, memory, sizeof memory);
    sum.memory = memory;
    print_run_summary(sum);
    if (companion_) print_companion_summary();
    if (odometry_) {
      const auto u = [](uint64_t v) { return static_cast<unsigned long long>(v); };
      std::printf("odometry: %s: %llu samples taken, %llu refused, %llu dropped (queue full)\n",
                  odometry_->description().c_str(), u(odometry_->received()),
                  u(odometry_->refused()), u(odometry_->dropped()));
    }
    outputs_->print_summary();
  }
  return code;
}

void Runtime::print_companion_summary() const {
  const Companion& co = *companion_;
  const Companion::Stats& st = co.stats();
  const CaptureChannel& ch = co.channel();
  const auto u = [](uint64_t v) { return static_cast<unsigned long long>(v); };
  const uint64_t poses = shared_.poses.load();
  const uint64_t valid = st.used[1] + st.used[2] + st.used[3];
  std::printf(
      "companion: %s on %s: %llu frames captured, %llu estimates (%llu valid by its own gate)\n"
      "  valid poses: %llu of %llu (both sensors %llu, own alone %llu, companion alone %llu); "
      "%llu cycles both valid but apart (fusion.max_position_spread_m / "
      "max_orientation_spread_deg); %llu cycles without a companion estimate within "
      "companion_max_age_ms; its estimates %.1f ms older than the cycle's frame on average, "
      "%.1f ms at most\n",
      co.config().model.c_str(), co.config().origin.c_str(), u(ch.captured.load()), u(st.estimates),
      u(st.valid), u(valid), u(poses), u(st.used[3]), u(st.used[1]), u(st.used[2]),
      u(st.disagreements), u(st.stale),
      poses > st.stale ? st.age_sum_ms / double(poses - st.stale) : 0.0, st.age_max_ms);
}

void Runtime::collect_stats() {
  stats_.frames_captured = channels_[0]->captured.load();
  stats_.frames_skipped = shared_.frames_skipped.load();
  stats_.frames_dropped = channels_[0]->slot->dropped();
  stats_.fusion_no_quorum = estimator_->no_quorum();
  stats_.sparse_scans = estimator_->sparse_scans();
  stats_.cameras.clear();
  for (const auto& c : channels_) {
    stats_.cameras.push_back(
        {c->captured.load(), c->missing, c->flagged, c->outliers, c->slot->dropped()});
  }
  stats_.poses = shared_.poses.load();
  stats_.poses_flagged = shared_.poses_flagged.load();
  stats_.deadline_misses = shared_.deadline_misses.load();
  stats_.ring_full = shared_.ring_full.load();
  stats_.reloads = models_->reloads();
  stats_.publish_failures_injected = publisher_->injected_publish_failures();
  stats_.reloads_refused = models_->refused();
}

void Runtime::write_saved_frame(const FrameBuffer& f, const PoseRecord& rec, const Engine& e) {
  FrameSidecar side;
  side.format = f.info.format;
  side.width = f.info.width;
  side.height = f.info.height;
  side.stride = f.info.stride;
  side.bytes = f.info.bytes;
  const PoseEstimate& p = rec.pose;
  const double pose[7] = {p.position[0],    p.position[1],    p.position[2],   p.orientation[0],
                          p.orientation[1], p.orientation[2], p.orientation[3]};
  std::copy(pose, pose + 7, side.pose);
  const std::string text =
      format_frame_sidecar(side, f.info.name, config_.model.c_str(), e.isa(), p.flags);
  FILE* raw = std::fopen(save_path_.c_str(), "wb");
  FILE* txt = std::fopen((save_path_ + ".txt").c_str(), "w");
  bool ok = raw && txt && std::fwrite(f.data, 1, f.info.bytes, raw) == f.info.bytes &&
            std::fwrite(text.data(), 1, text.size(), txt) == text.size();
  if (raw) ok = std::fclose(raw) == 0 && ok;
  if (txt) ok = std::fclose(txt) == 0 && ok;
  std::fprintf(stderr, "aprt run: %s frame %s to %s\n", ok ? "saved" : "could not save",
               f.info.name, save_path_.c_str());
}

Status Runtime::start_recording(const std::string& path, int ring_frames) {
  if (recorder_) return Error(Errc::kInvalidArgument, "record: already recording");
  CaptureChannel& trigger = *channels_[0];
  RecorderOptions o;
  o.path = path;
  o.max_frame_bytes = trigger.source->max_frame_bytes();
  o.scans = trigger.scans();
  o.ring_frames = ring_frames;
  o.frame_id = config_.output.frame_id;
  if (config_.output.dds.enabled) {
    o.pose_topic = config_.output.dds.pose_topic;
    o.diagnostics_topic = config_.output.dds.diagnostics_topic;
  }
  auto r = Recorder::create(o);
  if (!r) return r.error();
  recorder_ = std::move(r.value());
  trigger.recorder = recorder_.get();
  outputs_->set_recorder(recorder_.get());
  return ok();
}

Status Runtime::finish_recording(char* line, size_t size) {
  line[0] = '\0';
  if (!recorder_) return ok();
  Status s = recorder_->stop();
  recorder_summary(*recorder_, line, size);
  return s;
}

Status Runtime::write_timing_report(const char* json_path) const {
  TimingContext ctx;
  ctx.model = config_.model.c_str();
  const Config::Source& src = config_.source;
  switch (src.type) {
    case SourceType::kReplay:
    case SourceType::kLidarReplay:
    case SourceType::kMcap: ctx.source = src.replay.path.c_str(); break;
    case SourceType::kPointCloud2: ctx.source = src.pointcloud2.topic.c_str(); break;
    case SourceType::kLibcamera:
      ctx.source =
          src.libcamera.camera.empty() ? "libcamera camera 0" : src.libcamera.camera.c_str();
      break;
    case SourceType::kV4l2: ctx.source = src.v4l2.device.c_str(); break;
  }
  ctx.isa = models_->running().isa();
  ctx.threads = models_->running().threads();
  double hz = 0;  // 0: no camera period (a replay as fast as taken, a LiDAR's own rate)
  switch (src.type) {
    case SourceType::kReplay:
    case SourceType::kLidarReplay:
    case SourceType::kMcap: hz = src.replay.recorded ? 0 : src.replay.rate_hz; break;
    case SourceType::kPointCloud2: hz = 0; break;
    case SourceType::kLibcamera: hz = double(src.libcamera.fps); break;
    case SourceType::kV4l2: hz = double(src.v4l2.fps); break;
  }
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
  ctx.budget = budget_valid_ ? &budget_ : nullptr;
  ctx.duration_s = duration_s_;
  size_t n = 0;
  const TimingRecord* t = publisher_->timings(&n);
  return aprt::write_timing_report(json_path, t, n, stats_, ctx);
}

}  // namespace aprt
