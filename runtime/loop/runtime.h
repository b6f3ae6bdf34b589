// The supervised real-time loop that `aprt run` is:
//
//   capture threads   one per camera: source.next() -> its FrameSlot (latest
//                     frame, drops stale)
//   inference thread  FrameSlot -> preprocess -> Engine::run -> decode_pose
//                     -> sanity flags -> PoseRecord ring; with several cameras
//                     the first camera's frame starts a cycle, the others'
//                     newest frames (waited for up to fusion.max_frame_skew_ms)
//                     run back to back through the same engine, and their
//                     base_link poses are fused (runtime/pose/pose_fusion.h)
//   publish thread    PoseRecord ring -> console, base_link geometry, DDS, CAN;
//                     status (DiagnosticArray) at output.status_rate_hz
//   supervisor        the calling thread: health at a fixed rate, state,
//                     watchdog and systemd notifications, shutdown
//
// Everything is created by create(); after it, the capture -> publish path
// allocates nothing (the replay's image decoding aside, see drivers/replay),
// waits only with timeouts, and shares no lock with any other thread.
#pragma once

#include <pthread.h>

#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "drivers/frame/frame_slot.h"
#include "drivers/frame/frame_source.h"
#include "kernels/preprocess/lidar_input.h"
#include "kernels/preprocess/preprocess_image.h"
#include "runtime/config/config.h"
#include "runtime/engine/engine.h"
#include "runtime/loop/fault_injector.h"
#include "runtime/loop/pose_outputs.h"
#include "runtime/loop/pose_record.h"
#include "runtime/loop/spsc_ring.h"
#include "runtime/loop/supervisor.h"
#include "runtime/loop/timing_report.h"
#include "runtime/pose/pose_fusion.h"

namespace aprt {

// Per-frame stage timings for the exit summary and `--timing` reports.
struct TimingRecord {
  int64_t capture_ns, inference_start_ns, inference_end_ns, publish_ns;
};

// A state change as the supervisor made it (reason: a static string).
struct StateChange {
  RunState state;
  const char* reason;
  int64_t at_ns;
};

struct RunStats {
  uint64_t frames_captured = 0, frames_skipped = 0, frames_dropped = 0;
  uint64_t poses = 0, poses_flagged = 0, deadline_misses = 0, ring_full = 0;
  uint64_t source_restarts = 0;
  uint64_t reloads = 0, reloads_refused = 0;
  uint64_t publish_failures_injected = 0;
  // Multi-camera runs: fusion cycles without a quorum, and per camera
  // (configuration order) frames captured, cycles it had no frame in time,
  // estimates flagged, and estimates rejected as outliers.
  uint64_t fusion_no_quorum = 0;
  uint64_t sparse_scans = 0;  // LiDAR: scans with too few points (flagged estimates)
  struct Camera {
    uint64_t frames = 0, missing = 0, flagged = 0, outliers = 0, dropped = 0;
  };
  std::vector<Camera> cameras;
};

class Runtime {
 public:
  static Expected<std::unique_ptr<Runtime>> create(const Config& config);
  ~Runtime();

  // Runs until the replay ends, request_stop(), or FAULT. Returns the exit
  // code: 0 clean end or stop, 3 FAULT.
  int run();
  // Async-signal-safe.
  void request_stop() { stop_.store(true, std::memory_order_release); }
  // Async-signal-safe (SIGHUP): the supervisor reloads the configured model
  // file into a second engine, checks it (signature, file, fit) and the
  // inference thread switches to it between two frames; a bad file leaves the
  // running model in place, with the reason on stderr.
  void request_reload() { reload_requested_.store(true, std::memory_order_release); }

  const RunStats& stats() const { return stats_; }
  const Engine& engine() const { return *engine_; }
  const PoseOutputs& outputs() const { return *outputs_; }
  // Timing of every published pose, in order (capacity fixed at create()).
  const TimingRecord* timings(size_t* count) const {
    *count = timing_count_;
    return timings_.data();
  }
  // The process's allocation counter (allocation_counter.h), if the program
  // links one: sampled after the first published pose and at the end, for
  // the timing report's "allocations after start".
  void set_allocation_counter(uint64_t (*count)() noexcept, bool covers_malloc) {
    allocation_count_ = count;
    counter_covers_malloc_ = covers_malloc;
  }
  // The first kMaxStateChanges state changes of the run, in order.
  static constexpr size_t kMaxStateChanges = 64;
  const StateChange* state_changes(size_t* count) const {
    *count = state_change_count_;
    return state_changes_;
  }
  // Diagnostics: write the raw frame of pose `index` to `path` and, to
  // `path`.txt, its geometry and the pose computed for it (`aprt infer`
  // recomputes it elsewhere -- the HIL rig's VM-vs-host check). One file
  // write on the inference thread for that one frame; off by default.
  void save_frame(int64_t index, const std::string& path) {
    save_index_ = index;
    save_path_ = path;
  }
  // After run(): the timing validation report (timing_report.h).
  Status write_timing_report(const char* json_path) const;

 private:
  Runtime() = default;
  static void* inference_main(void* self);
  static void* publish_main(void* self);
  void inference_loop();
  void publish_loop();
  void print_pose(const PoseRecord& r);
  void print_summary();
  void service_reload();  // supervisor thread
  Status start_thread(pthread_t* t, void* (*fn)(void*), void* arg, const ThreadConfig& tc,
                      const char* name);

  // One camera: its source, frame slot, preprocessing and mounting.
  struct Channel {
    Runtime* owner = nullptr;
    size_t index = 0;
    std::string name, thread_name;
    std::string source_type;
    std::unique_ptr<FrameSource> source;
    std::unique_ptr<FrameSlot> slot;
    std::unique_ptr<kernels::PreprocessPlan> plan;  // cameras
    bool scans = false;                             // a LiDAR: scans, not images
    Eigen::Isometry3d base_from_sensor = Eigen::Isometry3d::Identity();
    std::atomic<bool> done{false}, failed{false};
    std::atomic<int64_t> beat{0};
    std::atomic<uint64_t> captured{0};
    uint64_t missing = 0, flagged = 0, outliers = 0;  // inference thread
    pthread_t thread{};
    bool started = false;
    bool replay() const { return source_type == "replay" || source_type == "lidar_replay"; }
  };
  static void* channel_main(void* channel);
  void capture_loop(Channel& c);
  // Inference thread: the frame of camera `i` for this cycle, waiting for it
  // until `deadline_ns`; null if none came (camera missing from the cycle).
  const FrameBuffer* take_frame(Channel& c, int64_t deadline_ns) noexcept;

  Config config_;
  std::unique_ptr<Engine> engine_;  // the model inference runs (owned by the supervisor side)
  std::unique_ptr<Engine> spare_;   // a reloaded model, until inference has switched to it
  std::atomic<Engine*> pending_{nullptr};  // supervisor -> inference: switch to this
  std::atomic<Engine*> retired_{nullptr};  // inference -> supervisor: no longer used
  std::atomic<bool> reload_requested_{false};
  uint64_t reloads_ = 0, reloads_refused_ = 0;
  std::vector<std::unique_ptr<Channel>> cameras_;  // [0] is the trigger
  std::unique_ptr<SpscRing<PoseRecord, 64>> ring_;
  std::unique_ptr<PoseOutputs> outputs_;
  Supervisor supervisor_{Config::Supervisor{}};

  std::atomic<bool> stop_{false};
  std::atomic<bool> inference_done_{false};
  std::atomic<int64_t> inference_beat_{0}, publish_beat_{0};
  std::atomic<int64_t> last_frame_ns_{0};
  std::atomic<uint64_t> poses_{0};
  std::atomic<uint32_t> last_flags_{0};
  std::atomic<uint8_t> state_{uint8_t(RunState::kStarting)};
  std::atomic<const char*> reason_{"starting"};  // static strings of the supervisor
  std::atomic<uint64_t> frames_skipped_{0}, ring_full_{0};
  std::atomic<uint64_t> poses_flagged_{0}, deadline_misses_{0};
  std::atomic<uint64_t> published_{0};
  std::atomic<uint64_t> output_errors_{0};
  uint64_t injected_publish_failures_ = 0;
  int64_t save_index_ = -1;
  std::string save_path_;
  void write_saved_frame(const FrameBuffer& f, const PoseRecord& rec,
                         const Engine& e);  // publish thread; read after join
  FaultInjector faults_;
  StateChange state_changes_[kMaxStateChanges] = {};
  size_t state_change_count_ = 0;
  uint64_t (*allocation_count_)() noexcept = nullptr;
  bool counter_covers_malloc_ = false;
  MemorySample steady_, warm_, end_;
  // RSS growth is measured from here: the first poses touch preallocated
  // pages (decoder buffers sized for the largest file, stacks) for the first time.
  static constexpr uint64_t kRssWarmupPoses = 1000;
  double duration_s_ = 0;

  pthread_t inference_{}, publish_{};
  bool threads_started_[2] = {};
  uint64_t fusion_no_quorum_ = 0;  // inference thread
  // A LiDAR model's input from a scan (kernels/preprocess/lidar_input.h): the
  // parameters from the model file, scratch for the configured point count.
  kernels::BevInputParams bev_input_{};
  kernels::PointsInputParams points_input_{};
  std::vector<float> scan_scratch_;
  std::vector<uint16_t> bev_counts_;
  uint32_t scan_input(Engine& e, const FrameBuffer& f);  // inference thread; returns flags
  // LiDAR runs: what the last scan brought (for the diagnostics), sparse scans so far.
  std::atomic<uint64_t> sparse_scans_{0};
  std::atomic<uint32_t> scan_points_{0}, scan_dropped_{0}, scan_clipped_{0};
  void join_threads();
  int64_t started_ns_ = 0;
  std::vector<TimingRecord> timings_;
  size_t timing_count_ = 0;
  std::vector<float> pos_errors_, rot_errors_;  // with ground truth, error_count_ of them
  size_t error_count_ = 0;
  RunStats stats_;
  int watchdog_fd_ = -1;
};

}  // namespace aprt
