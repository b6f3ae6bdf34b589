// A tensor as the engine runs it: shape, type and where its data lives.
#pragma once

#include <cstddef>
#include <cstdint>

#include "runtime/engine/model_format.h"

namespace aprt {

struct Tensor {
  const char* name = "";
  format::DType dtype = format::DType::kF32;
  format::TensorKind kind = format::TensorKind::kActivation;
  int rank = 0;
  int dims[format::kMaxRank] = {};
  size_t numel = 0;
  size_t bytes = 0;
  float scale = 0.0f;
  int32_t zero_point = 0;
  const Tensor* qscale = nullptr;  // per-channel quantisation scales (f32 constant), or null
  void* data = nullptr;  // bound at load(): weights in the model image, others in the arena

  bool is_const() const { return kind == format::TensorKind::kConst; }
  int last_dim() const { return dims[rank - 1]; }
  size_t rows() const { return numel / size_t(last_dim()); }
  float* f32() const { return static_cast<float*>(data); }
};

}  // namespace aprt
