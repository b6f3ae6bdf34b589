// The capture side of the loop: one channel per camera (or the one LiDAR),
// each with its source, its frame slot (latest frame wins, drops stale,
// never blocks), the engine input that turns its frames into the model's
// input, and its mounting on the vehicle. Each channel's thread runs
// capture_loop(); the inference thread takes frames with take_frame().
#pragma once

#include <pthread.h>

#include <Eigen/Geometry>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "drivers/input/frame_slot.h"
#include "drivers/input/frame_source.h"
#include "runtime/config/config.h"
#include "runtime/engine/engine_input.h"
#include "runtime/loop/fault_injector.h"
#include "runtime/loop/loop_shared.h"

namespace aprt {

class Recorder;

struct CaptureChannel {
  size_t index = 0;  // configuration order; 0 is the trigger of a fusion cycle
  std::string name, thread_name;
  SourceType source_type = SourceType::kReplay;
  std::unique_ptr<FrameSource> source;
  std::unique_ptr<FrameSlot> slot;
  std::unique_ptr<EngineInput> input;  // made by the engine: the model's input from a frame
  Eigen::Isometry3d base_from_sensor = Eigen::Isometry3d::Identity();
  // capture thread -> everyone
  std::atomic<bool> done{false}, failed{false};
  std::atomic<int64_t> beat{0};
  std::atomic<uint64_t> captured{0};
  uint64_t frame_limit = 0;
  bool source_started = false;   // a camera started at open_channel() (its thread does not again)
  Recorder* recorder = nullptr;  // the trigger camera's, when the run records (recorder.h)  // a
                                 // device's `frames`: done after this many (0: no limit)
  // inference thread only
  uint64_t missing = 0, flagged = 0, outliers = 0;
  pthread_t thread{};
  bool started = false;
  // What its thread shares with the run (set before the thread starts).
  size_t run_channels = 1;
  LoopShared* shared = nullptr;
  const FaultInjector* faults = nullptr;

  bool scans() const { return input->scans(); }
  bool replay() const {
    return source_type == SourceType::kReplay || source_type == SourceType::kLidarReplay ||
           source_type == SourceType::kMcap;
  }
};

// A configured camera (or LiDAR) opened for `engine`'s model: the source
// (before it, the model's modality is checked against it), its slot, the
// engine input for its frames; `frames` receives a replay's length. `count`:
// how many channels the run has (names and messages).
Expected<std::unique_ptr<CaptureChannel>> open_channel(const Config::Camera& cam, size_t index,
                                                       size_t count, const Engine& engine,
                                                       const std::string& model, size_t* frames);

// The capture thread of a channel (a CaptureChannel*) until stop or the end
// of its stream; messages name the channel when the run has several.
void* capture_thread(void* channel);

// Inference thread: c's newest frame, waiting for one until `deadline_ns`
// (bounded by kLoopWaitNs per wait); null if none came (or the source ended).
// @rt.
const FrameBuffer* take_frame(CaptureChannel& c, int64_t deadline_ns) noexcept;

}  // namespace aprt
