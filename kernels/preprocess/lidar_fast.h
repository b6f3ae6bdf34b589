// LiDAR preprocessing, the fast kernels (issue #5); each equals its
// reference in kernels/preprocess/lidar__ref.h exactly (same indices, same values).
// Portable C++ written for the compiler's vectoriser (structure-of-arrays,
// branch-free inner loops), built with -O3 -ffp-contract=off so the distance
// arithmetic rounds as the reference's does.
#pragma once

#include <cstddef>
#include <cstdint>

#include "kernels/preprocess/lidar_bev.h"
#include "runtime/base/lidar_point.h"

namespace aprt::kernels {

// counts: grid * grid * 2 uint16 of scratch.
void lidar_bev_histogram(const LidarPoint* p, size_t n, const BevParams& b, uint16_t* counts,
                         float* out);

// scratch: 4 * n floats (x, y, z and the running distances, structure of arrays).
bool lidar_fps(const LidarPoint* p, size_t n, size_t count, uint32_t* idx, float* scratch);

}  // namespace aprt::kernels
