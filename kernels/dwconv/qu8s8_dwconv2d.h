// The int8 depthwise convolution's arguments (scheme: kernels/gemm/qs8_gemm.h).
#pragma once

#include <cstddef>
#include <cstdint>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {

// int8 depthwise convolution: X uint8 NHWC (per-tensor zero point), W int8
// [KH][KW][C] per-channel symmetric, given to the fast kernels as floats
// (exact; packed once at load), y = act(mult[c] * acc + bias[c]).
struct QDwConvArgs {
  Conv2dShape shape;
  const uint8_t* x;
  int32_t a_zero;
  const float* w;  // [KH][KW][C], the int8 values as floats
  const float* mult;
  const float* bias;
  Act act;  // any: applied in fp32 after the epilogue
  float* y;
};
// The fast depthwise kernels accumulate in float, exact while the window has
// at most this many taps (255 * 127 * taps < 2^24).
inline constexpr int kMaxQDwTaps = 256;

// Output rows [oy0, oy1) of an int8 depthwise convolution: the reference
// (qu8s8_dwconv2d__ref.h has the arithmetic) and the ISAs' (qu8s8_dwconv2d__simd.cc).
void qu8s8_dwconv2d__avx512(const QDwConvArgs& a, int oy0, int oy1);
void qu8s8_dwconv2d__avx2(const QDwConvArgs& a, int oy0, int oy1);
void qu8s8_dwconv2d__neon(const QDwConvArgs& a, int oy0, int oy1);

}  // namespace aprt::kernels
