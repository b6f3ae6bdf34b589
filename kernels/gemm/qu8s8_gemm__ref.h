// int8 GEMM and activation quantisation, the scalar reference of the int8
// kernels (kernels/gemm/qs8_gemm.h has the scheme). Weights unpacked,
// W [n][k] as LINEAR stores them.
#pragma once

#include <cstddef>
#include <cstdint>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {

void qu8s8_gemm__ref(int m, int n, int k, const uint8_t* a, size_t lda, int32_t a_zero,
                     const int8_t* w, const float* mult, const float* bias, const float* residual,
                     size_t ldr, Act act, float* c, size_t ldc);

void f32_qu8_quantize__ref(size_t n, const float* x, float inv_scale, int32_t zero, uint8_t* q);

}  // namespace aprt::kernels
