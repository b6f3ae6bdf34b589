// Helpers for ops' prepare(): uniform, specific error messages.
#pragma once

#include <cmath>
#include <cstring>

#include "runtime/base/check.h"
#include "runtime/engine/op_node.h"

namespace aprt::ops {

Error op_error(const OpNode& node, Errc code, const char* format, ...)
    __attribute__((format(printf, 3, 4)));

#define APRT_OP_ENSURE(node, cond, code, ...)                           \
  do {                                                                  \
    if (!(cond)) return ::aprt::ops::op_error(node, code, __VA_ARGS__); \
  } while (0)

// Tensor `role` of `node` is f32, present, and (if `want_const`) a constant.
Status expect_f32(const OpNode& node, const Tensor* t, const char* role, bool want_const);

// `t` has exactly `rank` dims equal to `dims` (-1 = any).
Status expect_dims(const OpNode& node, const Tensor* t, const char* role, int rank,
                   const int* dims);

inline float param_f32(const OpNode& node, int i) {
  float f;
  std::memcpy(&f, &node.params[i], sizeof f);
  return f;
}

Status expect_act(const OpNode& node, int32_t act);

// int8 ops (FORMAT.md, "Quantised ops"): weights `w` are a symmetric i8
// constant with one per-tensor scale or `channels` per-channel scales.
Status expect_int8_weights(const OpNode& node, const Tensor* w, int channels);
// The op's input quantisation in params[at] (scale, f32 bits) and params[at + 1]
// (zero point): finite scale > 0, zero point in [0, 255].
Status expect_input_quantisation(const OpNode& node, int at, float* scale, int32_t* zero);
// Floats that hold `bytes` bytes, in whole 64-byte lines (int8 data in the
// engine's float-counted scratch and packed areas).
inline size_t floats_for_bytes(size_t bytes) {
  return (bytes + 63) / 64 * 16;
}

// Tasks for an m x n x k product: enough to keep `threads` busy, none much
// smaller than 64k multiply-adds. rows: in rows, whole mr tiles; panels: in
// nr-column panels. Task t covers rows.begin(t % rows.tasks) and panels
// .begin(t / rows.tasks).
void split_gemm(int m, int n, int k, int mr, int nr, int threads, Split* rows, Split* panels);

}  // namespace aprt::ops
