// What a model expects of its input, as the preprocessing kernels'
// parameters: an image's side length, channels and normalisation; a LiDAR
// model's histogram geometry or point sampling -- all from the metadata.
#pragma once

#include "kernels/preprocess/lidar_input.h"
#include "runtime/base/image.h"
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

inline kernels::BevInputParams bev_input_params(const ModelMeta& m) {
  kernels::BevInputParams p{{int(m.input_shape[1]), m.bev_cell_m, m.bev_x_min, m.bev_y_min,
                             m.bev_height_threshold_m, m.bev_clip_count},
                            {0, 0},
                            {1, 1}};
  for (int c = 0; c < 2 && c < m.norm_channels; ++c) {
    p.mean[c] = m.norm_mean[c];
    p.std[c] = m.norm_std[c];
  }
  return p;
}

inline kernels::PointsInputParams points_input_params(const ModelMeta& m) {
  kernels::PointsInputParams p{
      int(m.input_shape[1]), m.points_crop_radius_m, m.points_coord_scale_m, {}, {}};
  for (int c = 0; c < 6; ++c) {
    p.mean[c] = c < m.norm_channels ? m.norm_mean[c] : 0.0f;
    p.std[c] = c < m.norm_channels ? m.norm_std[c] : 1.0f;
  }
  return p;
}

}  // namespace aprt
