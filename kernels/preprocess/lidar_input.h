// A gated LiDAR scan to the network input, for both LiDAR modalities (issue
// #5; docs/lidar.md). `aprt run` and `aprt eval` call these, so the loop and
// the evaluation feed a model the same values; tools/aprt_tools/lidar_bev.py
// and lidar_points.py state the same transforms for training.
//
//   BEV    histogram (lidar_bev_histogram), then (v - mean) / std per channel;
//          out: [grid][grid][2].
//   points crop to x^2 + y^2 <= r^2, farthest-point sampling of `samples`
//          points, features abs = p / s, rel = (p - mean of the samples) / s,
//          then (f - mean) / std per channel; out: [samples][6].
//
// Work is bounded by the scan's point count (the point buffer's capacity).
#pragma once

#include <cstddef>
#include <cstdint>

#include "kernels/preprocess/lidar_bev.h"
#include "runtime/base/lidar_point.h"

namespace aprt::kernels {

struct BevInputParams {
  BevParams bev;
  float mean[2], std[2];
};

struct PointsInputParams {
  int samples;
  float crop_radius_m, coord_scale_m;
  float mean[6], std[6];
};

// What a scan gave: points left after the crop (points models), and whether
// there were enough for the model (otherwise the estimate is low-confidence:
// the points were padded by repetition, or, with none, the input is zeros).
struct LidarInputResult {
  size_t points = 0;
  bool enough = true;
};

// counts: grid * grid * 2 uint16 of scratch.
LidarInputResult lidar_bev_input(const BevInputParams& p, const LidarPoint* pts, size_t n,
                                 uint16_t* counts, float* out);

// Scratch for up to `max_points` points: floats.
size_t lidar_points_input_scratch(size_t max_points, int samples);
// fast: the vectorised farthest-point sampler (equal indices) instead of the reference.
LidarInputResult lidar_points_input(const PointsInputParams& p, const LidarPoint* pts, size_t n,
                                    bool fast, float* scratch, float* out);

}  // namespace aprt::kernels
