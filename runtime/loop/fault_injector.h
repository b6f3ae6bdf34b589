// Deliberate faults for test rigs (configuration key fault_injection,
// docs/configuration.md): each fault hits the stage it names at a given
// frame of that stage, so a test can assert the state change, the flags and
// the recovery it must cause. Fixed capacity, no allocation, one branch per
// query when nothing is configured -- the production loop carries it at no
// measurable cost and a production configuration simply has none.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/base/expected.h"
#include "runtime/config/fault_spec.h"

namespace aprt {

class FaultInjector {
 public:
  static constexpr int kMaxFaults = aprt::kMaxFaults;
  FaultInjector() = default;
  Status configure(const std::vector<FaultSpec>& faults);
  bool any() const noexcept { return n_ > 0; }

  // @rt: each stage asks with its own frame index (0-based).
  int64_t stall_ns(uint64_t capture_index) const noexcept {
    return n_ ? once(FaultKind::kCameraStall, capture_index) : 0;
  }
  int64_t hang_ns(uint64_t inference_index) const noexcept {
    return n_ ? once(FaultKind::kInferenceHang, inference_index) : 0;
  }
  int64_t overrun_ns(uint64_t inference_index) const noexcept {
    return n_ ? window_ns(FaultKind::kInferenceOverrun, inference_index) : 0;
  }
  bool nan_output(uint64_t inference_index) const noexcept {
    return n_ && in_window(FaultKind::kNanOutput, inference_index);
  }
  bool publish_failure(uint64_t pose_index) const noexcept {
    return n_ && in_window(FaultKind::kPublishFailure, pose_index);
  }
  // Blocks the calling thread in one system call for `ns` (poll(2) on a pipe
  // nobody writes), whatever the stop flag says: the injected hang is a
  // thread stuck in the kernel, like a read from a FIFO or a vanished device.
  static void block(int64_t ns) noexcept;

 private:
  int64_t once(FaultKind k, uint64_t i) const noexcept;
  int64_t window_ns(FaultKind k, uint64_t i) const noexcept;
  bool in_window(FaultKind k, uint64_t i) const noexcept;
  FaultSpec faults_[kMaxFaults];
  int n_ = 0;
};

}  // namespace aprt
