#include "runtime/engine/ops/op_common.h"

#include <cstdarg>
#include <cstdio>

namespace aprt::ops {

Error op_error(const OpNode& node, Errc code, const char* format, ...) {
  char msg[Error::kCapacity];
  va_list args;
  va_start(args, format);
  std::vsnprintf(msg, sizeof msg, format, args);
  va_end(args);
  return Error(code, "model_bin: op %d '%s' (%s): %s", node.index, node.name,
               format::op_name(node.code), msg);
}

Status expect_f32(const OpNode& node, const Tensor* t, const char* role, bool want_const) {
  APRT_OP_ENSURE(node, t != nullptr, Errc::kBadOp, "%s is missing", role);
  APRT_OP_ENSURE(node, t->dtype == format::DType::kF32, Errc::kShapeMismatch,
                 "%s '%s' is %s, expected f32", role, t->name, format::dtype_name(t->dtype));
  if (want_const) {
    APRT_OP_ENSURE(node, t->is_const(), Errc::kBadOp, "%s '%s' must be a constant", role, t->name);
  } else {
    APRT_OP_ENSURE(node, !t->is_const(), Errc::kBadOp, "%s '%s' must not be a constant", role,
                   t->name);
  }
  return ok();
}

Status expect_dims(const OpNode& node, const Tensor* t, const char* role, int rank,
                   const int* dims) {
  bool match = t->rank == rank;
  for (int i = 0; match && i < rank; ++i) match = dims[i] < 0 || t->dims[i] == dims[i];
  if (match) return ok();
  char want[64] = {}, have[64] = {};
  int w = 0, h = 0;
  for (int i = 0; i < rank; ++i) {
    w += std::snprintf(want + w, sizeof want - w, dims[i] < 0 ? "%s?" : "%s%d", i ? "x" : "",
                       dims[i]);
  }
  for (int i = 0; i < t->rank; ++i) {
    h += std::snprintf(have + h, sizeof have - h, "%s%d", i ? "x" : "", t->dims[i]);
  }
  return op_error(node, Errc::kShapeMismatch, "%s '%s' has shape %s, expected %s", role, t->name,
                  have, want);
}

Status expect_act(const OpNode& node, int32_t act) {
  APRT_OP_ENSURE(node, act >= 0 && act <= format::kMaxAct, Errc::kBadOp, "unknown activation %d",
                 act);
  return ok();
}

}  // namespace aprt::ops
