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

Status expect_int8_weights(const OpNode& node, const Tensor* w, int channels) {
  APRT_OP_ENSURE(node, w->is_const(), Errc::kBadTensor, "int8 weights '%s' must be a constant",
                 w->name);
  APRT_OP_ENSURE(node, w->zero_point == 0, Errc::kBadTensor,
                 "int8 weights '%s' have zero point %d (symmetric weights need 0)", w->name,
                 w->zero_point);
  APRT_OP_ENSURE(node, (w->scale > 0.0f) != (w->qscale != nullptr), Errc::kBadTensor,
                 "int8 weights '%s' need exactly one of a per-tensor scale or per-channel scales",
                 w->name);
  APRT_OP_ENSURE(node, !w->qscale || w->qscale->numel == size_t(channels), Errc::kBadTensor,
                 "int8 weights '%s' have %zu per-channel scales for %d output channels", w->name,
                 w->qscale ? w->qscale->numel : 0, channels);
  return ok();
}

Status expect_input_quantisation(const OpNode& node, int at, float* scale, int32_t* zero) {
  *scale = param_f32(node, at);
  *zero = node.params[at + 1];
  APRT_OP_ENSURE(node, std::isfinite(*scale) && *scale > 0.0f, Errc::kBadTensor,
                 "input quantisation scale %g (must be finite and > 0)", double(*scale));
  APRT_OP_ENSURE(node, *zero >= 0 && *zero <= 255, Errc::kBadTensor,
                 "input zero point %d out of range [0, 255]", *zero);
  return ok();
}

}  // namespace aprt::ops
