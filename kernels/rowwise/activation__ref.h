// Scalar activations, shared by every reference kernel's epilogue.
#pragma once

#include <cmath>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels::ref {

inline float sigmoid(float x) {
  // Stable for large |x|: never evaluates exp of a large positive number.
  if (x >= 0.0f) {
    const float e = std::exp(-x);
    return 1.0f / (1.0f + e);
  }
  const float e = std::exp(x);
  return e / (1.0f + e);
}

inline float apply_act(float x, Act act) {
  switch (act) {
    case Act::kNone: return x;
    case Act::kSilu: return x * sigmoid(x);
    case Act::kGelu: return 0.5f * x * (1.0f + std::erf(x * 0.70710678118654752f));
    case Act::kSigmoid: return sigmoid(x);
    case Act::kRelu: return x > 0.0f ? x : 0.0f;
  }
  return x;
}

}  // namespace aprt::kernels::ref
