// What a model expects of its input image, as the preprocessing kernel's
// parameters: side length, channels and normalisation from the metadata.
#pragma once

#include "kernels/common/image_types.h"
#include "runtime/engine/model_file.h"

namespace aprt {

inline kernels::PreprocessParams preprocess_params(const ModelMeta& m) {
  kernels::PreprocessParams pp{int(m.input_shape[1]), int(m.input_shape[3]), {}, {}};
  for (int c = 0; c < m.norm_channels && c < 3; ++c) {
    pp.mean[c] = m.norm_mean[c];
    pp.std[c] = m.norm_std[c];
  }
  return pp;
}

}  // namespace aprt
