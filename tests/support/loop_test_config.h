// The loop configuration the integration tests share: an untrained test model
// on a replay, no console, lenient deadlines and timeouts (sanitizer builds
// are slow), no systemd, no memory locking; sanity only against non-finite
// output (a test model's poses are anywhere).
#pragma once

#include <string>

#include "runtime/config/config.h"

namespace aprt::test {

inline Config loop_test_config(const std::string& model, SourceType type,
                               const std::string& replay) {
  Config c;
  c.model = model;
  c.source.type = type;
  c.source.replay.path = replay;
  c.source.replay.rate_hz = 0;  // as fast as inference takes frames
  c.output.console = false;
  c.output.summary = false;
  c.output.sigma_position_m = 2.0;
  c.output.sigma_orientation_deg = 3.0;
  c.sanity.bounds_margin = 10;
  c.sanity.max_jump_m = 0;
  c.supervisor.inference_deadline_ms = 10000;
  c.supervisor.frame_timeout_ms = 10000;
  c.supervisor.systemd = false;
  c.supervisor.fault_after_s = 600;  // untrained test models: insane output is DEGRADED, no more
  c.threads.lock_memory = false;
  return c;
}

}  // namespace aprt::test
