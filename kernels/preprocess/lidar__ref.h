// LiDAR preprocessing, the scalar references (issue #5): the BEV 2-bin
// histogram, the radius crop and farthest-point sampling.
#pragma once

#include <cstddef>
#include <cstdint>

#include "kernels/preprocess/lidar_bev.h"
#include "runtime/base/lidar_point.h"

namespace aprt::kernels {

// out: [grid][grid][2] (runtime/base/lidar_point.h). Points outside the grid are ignored.
void lidar_bev_histogram__ref(const LidarPoint* p, size_t n, const BevParams& b, float* out);

// Keeps the points with x^2 + y^2 <= radius^2, in place and in order; returns how many.
size_t lidar_radius_crop__ref(LidarPoint* p, size_t n, float radius);

// Farthest-point sampling of `count` indices into idx: idx[0] = 0, then each
// next point is the one farthest (squared x, y, z distance) from all chosen
// so far, the lowest index on a tie. With fewer than `count` points the
// sequence repeats them in order (deterministic padding) and false is
// returned: the caller flags the estimate as low confidence. dist: n floats.
bool lidar_fps__ref(const LidarPoint* p, size_t n, size_t count, uint32_t* idx, float* dist);

}  // namespace aprt::kernels
