// The supervisor's decisions (DESIGN.md section 8): states STARTING ->
// RUNNING <-> DEGRADED -> FAULT from heartbeats, frame age, inference time
// and output sanity, evaluated at a fixed rate. Pure logic, so tests can
// drive it with made-up health snapshots; runtime.cc feeds it.
#pragma once

#include <cstdint>

#include "runtime/config/config.h"
#include "runtime/loop/pose_record.h"
#include "runtime/pose/pose_gate.h"

namespace aprt {

struct Health {
  int64_t now_ns = 0;
  int64_t started_ns = 0;
  int64_t last_frame_ns = 0;  // arrival (monotonic) of the newest frame inference took; 0 = none
  int64_t capture_beat_ns = 0, inference_beat_ns = 0, publish_beat_ns = 0;
  uint64_t poses = 0;
  uint32_t last_flags = 0;     // flags of the newest pose
  uint64_t output_errors = 0;  // cumulative failed writes of the outputs (DDS, injected)
  bool source_failed = false;
  bool end_of_stream = false;
  bool frame_limit = false;  // ... because a device source delivered its configured `frames`
};

class Supervisor {
 public:
  explicit Supervisor(const Config::Supervisor& cfg) : cfg_(cfg) {}

  // @rt: no allocation; updates and returns the state.
  RunState step(const Health& h) noexcept;
  RunState state() const { return state_; }
  const char* reason() const { return reason_; }
  // True when every stage beat recently: only then is the watchdog petted.
  // (The snapshot step() last judged, after its freeze allowance.)
  bool stages_alive() const noexcept { return alive_; }
  // Whole-process freezes seen (SIGSTOP, a paused VM): the gap between two
  // steps was longer than a frame timeout.
  uint64_t freezes() const { return freezes_; }

 private:
  void set(RunState s, const char* why) noexcept;
  bool alive(const Health& h) const noexcept;
  Health after_freeze(const Health& h) noexcept;
  Config::Supervisor cfg_;
  RunState state_ = RunState::kStarting;
  const char* reason_ = "starting";
  int64_t degraded_since_ns_ = 0;
  uint64_t output_errors_seen_ = 0;
  int64_t last_step_ns_ = 0;
  int64_t resumed_ns_ = 0;  // when the last freeze ended; 0 = none
  uint64_t freezes_ = 0;
  bool alive_ = true;
};

}  // namespace aprt
