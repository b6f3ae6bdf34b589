#pragma once

#include <cstddef>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {

// y[i] = a[i] + b[i]
void f32_add__ref(size_t n, const float* a, const float* b, float* y);
// y[i] = act(x[i])
void f32_activation__ref(size_t n, Act act, const float* x, float* y);
// In place, each of rows [r0, r1) of an [rows][n] matrix: x = exp(x - max) / sum.
void f32_softmax_rows__ref(int n, float* x, int r0, int r1);
// Row-wise concatenation: y[r] = x0[r] ++ x1[r] ++ ...; widths[i] columns from xs[i].
void f32_concat_rows__ref(int rows, int count, const float* const* xs, const int* widths, float* y);

}  // namespace aprt::kernels
