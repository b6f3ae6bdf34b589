// A source of camera frames, driven by the capture thread: replay, V4L2,
// libcamera. The capture thread calls next() in a loop; next() fills the
// buffer (the FrameSlot's back buffer) and returns, or reports why it did not.
#pragma once

#include <cstdint>

#include "drivers/input/frame.h"
#include "runtime/base/clock.h"
#include "runtime/base/expected.h"

namespace aprt {

class FrameSlot;

enum class SourceResult {
  kFrame,        // `dst` holds a new frame
  kTimeout,      // nothing within the timeout (the thread still beats its heartbeat)
  kSkipped,      // a frame was lost (corrupt, truncated): counted, not delivered
  kEndOfStream,  // a replay reached its end
  kFailed,       // the device failed; `error()` says why; the supervisor restarts it
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual const char* name() const = 0;
  // Largest frame in bytes (sizes the FrameSlot).
  virtual size_t max_frame_bytes() const = 0;
  // True when next() stamps capture_ns with the device's own capture time
  // (CLOCK_MONOTONIC); otherwise the capture thread stamps the arrival.
  virtual bool driver_timestamps() const { return false; }
  // Whether its frames carry the vehicle's motion (FrameInfo::has_motion).
  virtual bool has_odometry() const { return false; }
  virtual Status start() = 0;
  // Waits at most timeout_ns. Never allocates for a device source.
  virtual SourceResult next(FrameBuffer* dst, int64_t timeout_ns) = 0;
  virtual void stop() = 0;
  // The last failure or skip reason (valid until the next call).
  virtual const Error& error() const = 0;
  // Replays paced by their consumer (rate 0): the slot it takes from, and how
  // many frames it has taken. Devices ignore both.
  virtual void pace_with(const FrameSlot*) {}
  virtual void note_taken(uint64_t) {}
};

}  // namespace aprt
