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

namespace aprt {

enum class FaultKind : uint8_t {
  kCameraStall,       // capture delivers nothing for duration_ms (at capture frame at_frame)
  kInferenceOverrun,  // inference takes duration_ms longer, for `count` frames
  kNanOutput,         // the network output is NaN, for `count` frames
  kPublishFailure,    // the outputs' writes fail, for `count` poses
  kInferenceHang,     // the inference thread stops beating for duration_ms (at at_frame)
};

struct FaultSpec {
  FaultKind kind = FaultKind::kCameraStall;
  uint64_t at_frame = 0;
  uint64_t count = 1;
  double duration_ms = 0;
};

// "camera_stall" ... -> kind; false for an unknown name.
bool fault_kind_from_name(const std::string& name, FaultKind* out);
const char* fault_kind_name(FaultKind k);

class FaultInjector {
 public:
  static constexpr int kMaxFaults = 8;
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

 private:
  int64_t once(FaultKind k, uint64_t i) const noexcept;
  int64_t window_ns(FaultKind k, uint64_t i) const noexcept;
  bool in_window(FaultKind k, uint64_t i) const noexcept;
  FaultSpec faults_[kMaxFaults];
  int n_ = 0;
};

}  // namespace aprt
