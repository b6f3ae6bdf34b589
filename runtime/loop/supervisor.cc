#include "runtime/loop/supervisor.h"

#include <algorithm>

namespace aprt {

const char* run_state_name(RunState s) {
  switch (s) {
    case RunState::kStarting: return "STARTING";
    case RunState::kRunning: return "RUNNING";
    case RunState::kDegraded: return "DEGRADED";
    case RunState::kFault: return "FAULT";
    case RunState::kStopping: return "STOPPING";
  }
  return "?";
}

void Supervisor::set(RunState s, const char* why) noexcept {
  state_ = s;
  reason_ = why;
}

bool Supervisor::alive(const Health& h) const noexcept {
  // A stage that has not beaten for two frame timeouts is hung.
  const int64_t limit = int64_t(2.0 * cfg_.frame_timeout_ms * 1e6);
  return h.now_ns - h.capture_beat_ns < limit && h.now_ns - h.inference_beat_ns < limit &&
         h.now_ns - h.publish_beat_ns < limit;
}

// The supervisor ticks at rate_hz at a high priority: a gap of more than a
// frame timeout between two of its steps means the whole process stood still
// (SIGSTOP/SIGCONT, a paused VM, a debugger), not that one stage hung --
// every beat and the newest frame are old by the same gap. For two frame
// timeouts after such a gap, nothing is judged older than the moment the
// process resumed: stages that beat again by then are well; a stage that
// still does not is hung (FAULT), as before.
Health Supervisor::after_freeze(const Health& h) noexcept {
  const int64_t timeout = int64_t(cfg_.frame_timeout_ms * 1e6);
  if (last_step_ns_ != 0 && h.now_ns - last_step_ns_ > timeout) {
    resumed_ns_ = h.now_ns;
    ++freezes_;
  }
  last_step_ns_ = h.now_ns;
  Health g = h;
  if (resumed_ns_ != 0 && h.now_ns - resumed_ns_ < 2 * timeout) {
    g.capture_beat_ns = std::max(g.capture_beat_ns, resumed_ns_);
    g.inference_beat_ns = std::max(g.inference_beat_ns, resumed_ns_);
    g.publish_beat_ns = std::max(g.publish_beat_ns, resumed_ns_);
    if (g.last_frame_ns != 0) g.last_frame_ns = std::max(g.last_frame_ns, resumed_ns_);
    // The pose in flight during the freeze is late by the freeze, not by a
    // slow stage: its deadline and staleness flags say nothing of health.
    g.last_flags &= ~(kPoseDeadlineMissed | kPoseStaleFrame);
  }
  return g;
}

RunState Supervisor::step(const Health& health) noexcept {
  const Health h = after_freeze(health);
  alive_ = alive(h);
  if (state_ == RunState::kFault || state_ == RunState::kStopping) return state_;
  if (h.end_of_stream) {
    set(RunState::kStopping, h.frame_limit ? "the source delivered its configured frames"
                                           : "end of the replayed sequence");
    return state_;
  }
  if (!alive_) {
    set(RunState::kFault, "a stage stopped beating (hung thread)");
    return state_;
  }
  const int64_t timeout = int64_t(cfg_.frame_timeout_ms * 1e6);
  const char* problem = nullptr;
  const bool outputs_failing = h.output_errors > output_errors_seen_;
  output_errors_seen_ = h.output_errors;
  if (h.source_failed) {
    problem = "sensor source failed (restarting)";
  } else if (h.last_frame_ns == 0) {
    if (h.now_ns - h.started_ns > timeout) problem = "no frame received yet";
  } else if (h.now_ns - h.last_frame_ns > timeout) {
    problem = "frames stale (sensor stalled?)";
  } else if (h.last_flags & kPoseDeadlineMissed) {
    problem = "inference deadline missed";
  } else if (h.last_flags & (kPoseNonFinite | kPoseQuatDegenerate | kPoseQuatNorm)) {
    problem = "network output not sane";
  } else if (h.last_flags & kPoseOutOfBounds) {
    problem = "pose implausible (outside the map)";
  } else if (h.last_flags & kPoseStaleFrame) {
    problem = "frames arrive late";
  } else if (outputs_failing) {
    problem = "outputs failing (write errors)";
  }
  if (problem) {
    if (state_ != RunState::kDegraded) degraded_since_ns_ = h.now_ns;
    set(RunState::kDegraded, problem);
    if (h.now_ns - degraded_since_ns_ > int64_t(cfg_.fault_after_s * 1e9)) {
      set(RunState::kFault, problem);
    }
  } else if (h.poses > 0) {
    // A pose the validity gate withholds is normal operation (the model is
    // not sure, or disagrees with the motion): the state stays RUNNING and
    // the reason says why the pose did not go out as valid.
    const char* why = "ok";
    if (h.last_flags & kPoseJump) {
      why = "ok; pose withheld: an implausible jump from the last pose";
    } else if (h.last_flags & kPoseNoOdometry) {
      why = "ok; pose withheld: no vehicle motion for the pose filter (odometry)";
    } else if (h.last_flags & kPoseUncertain) {
      why = "ok; pose withheld: the model (or the pose filter) is not confident enough";
    } else if (h.last_flags & kPoseInconsistent) {
      why = "ok; pose withheld: it disagrees with the vehicle's motion";
    } else if (h.last_flags & kPoseUnconfirmed) {
      why = "ok; pose withheld: no confirmed track yet";
    }
    set(RunState::kRunning, why);
  }
  return state_;
}

}  // namespace aprt
