// The training transform as a fused, table-driven pass: source indices and
// weights for every output row and column are computed once when the camera
// geometry is known (plan), so a frame costs four neighbour fetches, a
// colour conversion and a normalisation per output pixel -- no allocation,
// no division. Results equal preprocess_image__ref (same arithmetic order).
#pragma once

#include "kernels/common/image_types.h"

namespace aprt::kernels {

struct PreprocessPlan {
  static constexpr int kMaxSize = 512;
  PreprocessParams params;
  int width = 0, height = 0;  // the frame geometry the plan is for
  PixelFormat format = PixelFormat::kRgb24;
  int x0[kMaxSize], x1[kMaxSize], y0[kMaxSize], y1[kMaxSize];  // absolute pixel indices
  float wx[kMaxSize], wy[kMaxSize];
};

// false if the geometry is unusable (size > kMaxSize, empty frame, ...).
bool plan_preprocess(const PreprocessParams& p, PixelFormat format, int width, int height,
                     PreprocessPlan* plan);

// @rt: out = the network input (NHWC float). img must match the plan's geometry.
void preprocess_image(const PreprocessPlan& plan, const ImageView& img, float* out);

}  // namespace aprt::kernels
