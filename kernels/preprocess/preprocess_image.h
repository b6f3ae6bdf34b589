// The training transform as a fused, table-driven pass: source indices and
// weights for every output row and column are computed once when the camera
// geometry is known (plan), so a frame costs four neighbour fetches, a
// colour conversion and a normalisation per output pixel -- no allocation,
// no division. The portable loop equals u8_f32_preprocess__ref (same arithmetic
// order); the ISA kernels (simd/preprocess_impl.inl) are within a few ulp.
#pragma once

#include "runtime/base/image.h"

namespace aprt::kernels {

// The training transform (docs/preprocessing.md): centre square crop, bilinear
// resize with half-pixel centres to size x size, values / 255, then
// (v - mean[c]) / std[c]; output NHWC float [size][size][3] (or 1 channel).
struct PreprocessParams {
  int size;
  int channels;  // 3 (RGB) or 1 (gray)
  float mean[3];
  float std[3];
};

struct PreprocessPlan {
  static constexpr int kMaxSize = 512;
  PreprocessParams params;
  int width = 0, height = 0;  // the frame geometry the plan is for
  PixelFormat format = PixelFormat::kRgb24;
  int x0[kMaxSize], x1[kMaxSize], y0[kMaxSize], y1[kMaxSize];  // absolute pixel indices
  float wx[kMaxSize], wy[kMaxSize];
  // The ISA's kernel (KernelSet::preprocess), chosen when planning; null: the
  // portable table-driven loop below.
  void (*fast)(const PreprocessPlan& plan, const ImageView& img, float* out) = nullptr;
};

// false if the geometry is unusable (size > kMaxSize, empty frame, ...).
// `fast`: the ISA kernel to use (the engine's KernelSet::preprocess), or null.
// Re-planning (a camera renegotiated) keeps the plan's kernel when `fast` is null.
bool plan_preprocess(const PreprocessParams& p, PixelFormat format, int width, int height,
                     PreprocessPlan* plan,
                     void (*fast)(const PreprocessPlan&, const ImageView&, float*) = nullptr);

// The portable loop, whatever the plan's kernel (tests, benchmarks).
void preprocess_image_portable(const PreprocessPlan& plan, const ImageView& img, float* out);

// @rt: out = the network input (NHWC float). img must match the plan's geometry.
void preprocess_image(const PreprocessPlan& plan, const ImageView& img, float* out);

}  // namespace aprt::kernels
