#include "runtime/config/fault_spec.h"

namespace aprt {

namespace {

struct Named {
  const char* name;
  FaultKind kind;
};
constexpr Named kNames[] = {
    {"camera_stall", FaultKind::kCameraStall},
    {"inference_overrun", FaultKind::kInferenceOverrun},
    {"nan_output", FaultKind::kNanOutput},
    {"publish_failure", FaultKind::kPublishFailure},
    {"inference_hang", FaultKind::kInferenceHang},
};

}  // namespace

bool fault_kind_from_name(const std::string& name, FaultKind* out) {
  for (const Named& n : kNames) {
    if (name == n.name) {
      *out = n.kind;
      return true;
    }
  }
  return false;
}

const char* fault_kind_name(FaultKind k) {
  for (const Named& n : kNames) {
    if (n.kind == k) return n.name;
  }
  return "?";
}

}  // namespace aprt
