// The vehicle's live odometry for the pose filter (odometry.source: dds or
// can): a thread (aprt-odometry) takes the twists a ROS 2 topic carries
// (drivers/input/twist/twist_reader.h), or the speed and yaw rate the
// vehicle's CAN bus carries (drivers/input/can_odometry/can_odometry.h,
// the same TwistSamples), and hands them to the inference
// thread through a lock-free queue; the inference thread integrates them
// into its own OdometryTrack and asks it for the reading at each frame's
// time. Neither thread waits for the other: a full queue drops (and counts)
// twists, which shows as a gap (a new odometry epoch) to the filter.
#pragma once

#include <pthread.h>

#include <atomic>
#include <cstdint>
#include <memory>

#include "drivers/input/odometry.h"
#include "drivers/input/twist/twist_reader.h"
#include "runtime/base/expected.h"
#include "runtime/config/config.h"
#include "runtime/loop/spsc_ring.h"

namespace aprt {

class OdometryInput {
 public:
  // Opens the topic or the CAN interface and starts the thread.
  static Expected<std::unique_ptr<OdometryInput>> create(const Config::Odometry& c);
  ~OdometryInput();
  OdometryInput(const OdometryInput&) = delete;
  OdometryInput& operator=(const OdometryInput&) = delete;

  // The inference thread: the reading at `realtime_ns` (the frame's time on
  // the twists' clock), after taking in what arrived. @rt.
  OdometryReading reading_at(int64_t realtime_ns) noexcept;

  uint64_t received() const { return received_.load(std::memory_order_relaxed); }
  uint64_t refused() const { return refused_.load(std::memory_order_relaxed); }
  uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }
  int publishers() const { return reader_->publishers(); }
  // "dds <topic>" or "can <interface> <speed signal> + <yaw-rate signal>".
  const std::string& description() const { return description_; }

 private:
  OdometryInput() = default;
  void run() noexcept;

  std::unique_ptr<TwistReader> reader_;
  std::string description_;
  SpscRing<TwistSample, 1024> queue_;
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> received_{0}, refused_{0}, dropped_{0};
  pthread_t thread_{};
  bool started_ = false;
  // The inference thread's.
  OdometryTrack track_;
  int64_t origin_ns_ = 0;  // the first twist's stamp: the track's clock starts there
  bool have_origin_ = false;
};

}  // namespace aprt
