// Deliberate faults for test rigs, as the configuration names them
// (fault_injection; docs/configuration.md). The loop's FaultInjector
// (runtime/loop/fault_injector.h) applies them.
#pragma once

#include <cstdint>
#include <string>

namespace aprt {

enum class FaultKind : uint8_t {
  kCameraStall,       // capture delivers nothing for duration_ms (at capture frame at_frame)
  kInferenceOverrun,  // inference takes duration_ms longer, for `count` frames
  kNanOutput,         // the network output is NaN, for `count` frames
  kPublishFailure,    // the outputs' writes fail, for `count` poses
  kInferenceHang,     // the inference thread stops beating for duration_ms (at at_frame)
};

// At most this many faults in one configuration.
inline constexpr int kMaxFaults = 8;

struct FaultSpec {
  FaultKind kind = FaultKind::kCameraStall;
  uint64_t at_frame = 0;
  uint64_t count = 1;
  double duration_ms = 0;
};

// "camera_stall" ... -> kind; false for an unknown name.
bool fault_kind_from_name(const std::string& name, FaultKind* out);
const char* fault_kind_name(FaultKind k);

}  // namespace aprt
