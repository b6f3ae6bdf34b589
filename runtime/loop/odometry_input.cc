#include "runtime/loop/odometry_input.h"

#include <new>

#include "drivers/input/can_odometry/can_odometry.h"
#include "runtime/base/clock.h"
#include "runtime/loop/rt_thread.h"

namespace aprt {

Expected<std::unique_ptr<OdometryInput>> OdometryInput::create(const Config::Odometry& c) {
  std::unique_ptr<OdometryInput> in(new (std::nothrow) OdometryInput());
  if (!in) return Error(Errc::kOutOfMemory, "odometry: out of memory");
  if (c.source == "can") {
    auto r = CanTwistReader::create(c.can);
    if (!r) return r.error();
    in->description_ = "can " + c.can.interface + " " + r.value()->description();
    in->reader_ = std::move(r.value());
  } else {
    TwistOptions o;
    o.domain = uint32_t(c.domain);
    o.topic = c.topic;
    o.reliable = c.reliable;
    o.loopback_only = c.loopback_only;
    o.depth = c.depth;
    auto r = TwistReader::create(o);
    if (!r) return Error(r.error().code(), "odometry: %s", r.error().message());
    in->reader_ = std::move(r.value());
    in->description_ = "dds " + c.topic;
  }
  // Normal scheduling: nothing waits for it, and it waits for the bus only;
  // the stack of the loop's threads that call into the DDS library.
  if (Status st = start_thread(
          &in->thread_,
          [](void* self) -> void* {
            static_cast<OdometryInput*>(self)->run();
            return nullptr;
          },
          in.get(), ThreadConfig{}, "aprt-odometry", 512 * 1024);
      !st) {
    return Error(st.error().code(), "odometry: %s", st.error().message());
  }
  in->started_ = true;
  return in;
}

OdometryInput::~OdometryInput() {
  stop_.store(true, std::memory_order_release);
  // take() waits 100 ms at most.
  if (started_) (void)join_thread_by(thread_, monotonic_ns() + 2000000000);
}

void OdometryInput::run() noexcept {
  TwistSample batch[32];
  while (!stop_.load(std::memory_order_acquire)) {
    const int n = reader_->take(batch, 32, 100000000);
    for (int i = 0; i < n; ++i) {
      if (!queue_.push(batch[i])) dropped_.fetch_add(1, std::memory_order_relaxed);
    }
    received_.store(reader_->stats().received, std::memory_order_relaxed);
    refused_.store(reader_->stats().refused, std::memory_order_relaxed);
  }
}

OdometryReading OdometryInput::reading_at(int64_t realtime_ns) noexcept {
  TwistSample s;
  while (queue_.pop(&s)) {
    if (!have_origin_) {
      origin_ns_ = s.stamp_ns;
      have_origin_ = true;
    }
    track_.add({double(s.stamp_ns - origin_ns_) * 1e-9, s.speed_mps, s.yaw_rate_radps});
  }
  if (!have_origin_) return {};
  return track_.at(double(realtime_ns - origin_ns_) * 1e-9);
}

}  // namespace aprt
