// The supervised real-time loop that `aprt run` is, put together from its
// parts:
//
//   capture threads   one per camera (or the LiDAR): capture.h -- source ->
//                     its FrameSlot (latest frame, drops stale)
//   inference thread  FrameSlots -> Estimator (estimator.h: engine input,
//                     Engine::run, decode, base_link, fusion, checks) ->
//                     PoseRecord ring; with several cameras the first one's
//                     frame starts a cycle and the others' newest frames
//                     (waited for up to fusion.max_frame_skew_ms) join it
//   publish thread    Publisher (publisher.h): ring -> console, DDS, CAN,
//                     status at output.status_rate_hz
//   supervisor        the calling thread: health at a fixed rate ->
//                     Supervision (supervision.h: states, watchdog,
//                     systemd), model reloads (model_slot.h)
//   report            run_report.h, timing_report.h, after the run
//
// Everything is created by create(); after it, the capture -> publish path
// allocates nothing (the replay's image decoding aside, see drivers/input/replay),
// waits only with timeouts, and shares no lock with any other thread.
#pragma once

#include <pthread.h>

#include <memory>
#include <string>
#include <vector>

#include "runtime/config/config.h"
#include "runtime/engine/engine.h"
#include "runtime/loop/capture.h"
#include "runtime/loop/companion.h"
#include "runtime/loop/estimator.h"
#include "runtime/loop/fault_injector.h"
#include "runtime/loop/loop_shared.h"
#include "runtime/loop/model_slot.h"
#include "runtime/loop/odometry_input.h"
#include "runtime/loop/pose_outputs.h"
#include "runtime/loop/process_memory.h"
#include "runtime/loop/publisher.h"
#include "runtime/loop/recorder.h"
#include "runtime/loop/run_stats.h"
#include "runtime/loop/supervision.h"
#include "runtime/loop/timing_report.h"

namespace aprt {

class Runtime {
 public:
  // `companion`: the configuration of fusion.companion, its paths resolved
  // (companion.h); null: none.
  static Expected<std::unique_ptr<Runtime>> create(const Config& config,
                                                   const Config* companion = nullptr);
  ~Runtime();

  // Runs until the replay ends, request_stop(), or FAULT. Returns the exit
  // code: 0 clean end or stop, 3 FAULT.
  int run();
  // Async-signal-safe.
  void request_stop() { shared_.stop.store(true, std::memory_order_release); }
  // Async-signal-safe (SIGHUP): the supervisor reloads the configured model
  // (model_slot.h); a bad file leaves the running model in place.
  void request_reload() { models_->request_reload(); }

  const RunStats& stats() const { return stats_; }
  const Engine& engine() const { return models_->running(); }
  const PoseOutputs& outputs() const { return *outputs_; }
  // The second sensor (fusion.companion), or null.
  const Companion* companion() const { return companion_.get(); }
  // Timing of every published pose, in order (capacity fixed at create()).
  const TimingRecord* timings(size_t* count) const { return publisher_->timings(count); }
  // The process's allocation counter (allocation_counter.h), if the program
  // links one: sampled after the first published pose and at the end, for
  // the timing report's "allocations after start".
  void set_allocation_counter(uint64_t (*count)() noexcept, bool covers_malloc) {
    allocation_count_ = count;
    counter_covers_malloc_ = covers_malloc;
  }
  static constexpr size_t kMaxStateChanges = Supervision::kMaxStateChanges;
  // The first kMaxStateChanges state changes of the run, in order.
  const StateChange* state_changes(size_t* count) const {
    return supervision_->state_changes(count);
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
  // Before run(): record the drive into `path` (recorder.h; the trigger
  // camera's frames, every pose, the diagnostics). After run(): the file is
  // closed and its summary line written to `line`.
  Status start_recording(const std::string& path, int ring_frames);
  Status finish_recording(char* line, size_t size);

 private:
  Runtime() = default;
  static void* inference_main(void* self);
  static void* publish_main(void* self);
  void inference_loop();
  // The companion's newest estimate fused into `rec` (inference thread); the pose's flags.
  uint32_t fuse_companion(PoseRecord* rec, uint32_t flags) noexcept;
  Health health(int64_t now_ns) const;
  void sample_memory();
  void collect_stats();
  void print_companion_summary() const;
  void write_saved_frame(const FrameBuffer& f, const PoseRecord& rec, const Engine& e);
  // Joins every started thread by `deadline_ns` (monotonic); the name of the
  // first that did not stop by then, or nullptr.
  const char* join_threads_by(int64_t deadline_ns);
  [[noreturn]] void exit_stuck(const char* stage, int code);

  Config config_;
  LoopShared shared_;
  FaultInjector faults_;
  std::unique_ptr<ModelSlot> models_;
  std::vector<std::unique_ptr<CaptureChannel>> channels_;  // [0] is the trigger
  std::vector<CaptureChannel*> channel_ptrs_;
  std::unique_ptr<OdometryInput> odometry_;  // odometry.source dds with the filter, or null
  std::unique_ptr<Estimator> estimator_;
  std::unique_ptr<Companion> companion_;  // fusion.companion, or null
  FaultInjector no_faults_;               // the companion's capture thread injects none
  SensorFusionParams sensor_fusion_;
  double own_sigma_pos_m_ = 1, own_sigma_rot_rad_ = 0.1;  // the run's model without sigma
  ValidStreak own_streak_;
  std::unique_ptr<PoseRing> ring_;
  std::unique_ptr<PoseOutputs> outputs_;
  std::unique_ptr<Publisher> publisher_;
  std::unique_ptr<Supervision> supervision_;
  std::unique_ptr<Recorder> recorder_;  // declared after what offers to it: destroyed first
  pthread_t inference_{}, publish_{};
  bool inference_started_ = false, publish_started_ = false;

  int64_t started_ns_ = 0;
  double duration_s_ = 0;
  int64_t save_index_ = -1;
  std::string save_path_;
  uint64_t (*allocation_count_)() noexcept = nullptr;
  bool counter_covers_malloc_ = false;
  MemorySample steady_, warm_, end_;
  // RSS growth is measured from here: the first poses touch preallocated
  // pages (decoder buffers sized for the largest file, stacks) for the first time.
  static constexpr uint64_t kRssWarmupPoses = 1000;
  // Where the memory is (process_memory.h), once a second's poses are out.
  static constexpr uint64_t kBudgetPoses = 25;
  MemoryBudget budget_;
  bool budget_valid_ = false;
  void measure_budget();
  // Every stage waits with timeouts of at most kLoopWaitNs, so a stop takes
  // milliseconds; a stage still running after this is blocked in the kernel
  // (a read that never returns), and the process ends without it: a FAULT
  // must end the process (docs/supervision.md).
  static constexpr int64_t kStopBoundNs = 1500000000;
  RunStats stats_;
};

}  // namespace aprt
