// The bird's-eye histogram's geometry (DESIGN.md 4.2; docs/lidar.md).
#pragma once

namespace aprt::kernels {

// The BEV image: grid x grid cells of cell_m, row r covers x in
// [x_min + r cell, x_min + (r + 1) cell), column c covers y likewise from
// y_min; channel 0 counts points with z < height_threshold_m, channel 1 the
// rest; each count clipped to clip_count and divided by it (values in [0, 1]),
// NHWC [grid][grid][2]. Every parameter comes from the model file.
struct BevParams {
  int grid;
  float cell_m;
  float x_min, y_min;
  float height_threshold_m;
  float clip_count;
};

}  // namespace aprt::kernels
