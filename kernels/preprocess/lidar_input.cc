#include "kernels/preprocess/lidar_input.h"

#include <cstring>

#include "kernels/preprocess/lidar__ref.h"
#include "kernels/preprocess/lidar_fast.h"

namespace aprt::kernels {

LidarInputResult lidar_bev_input(const BevInputParams& p, const LidarPoint* pts, size_t n,
                                 uint16_t* counts, float* out) {
  lidar_bev_histogram(pts, n, p.bev, counts, out);
  const size_t cells = size_t(p.bev.grid) * size_t(p.bev.grid);
  if (p.mean[0] != 0.0f || p.mean[1] != 0.0f || p.std[0] != 1.0f || p.std[1] != 1.0f) {
    for (size_t i = 0; i < cells; ++i) {
      out[2 * i] = (out[2 * i] - p.mean[0]) / p.std[0];
      out[2 * i + 1] = (out[2 * i + 1] - p.mean[1]) / p.std[1];
    }
  }
  LidarInputResult r;
  r.points = n;
  r.enough = n > 0;
  return r;
}

size_t lidar_points_input_scratch(size_t max_points, int samples) {
  // cropped copy (4 floats a point), the sampler's 4 n floats, the indices
  return 4 * max_points + 4 * max_points + size_t(samples);
}

LidarInputResult lidar_points_input(const PointsInputParams& p, const LidarPoint* pts, size_t n,
                                    bool fast, float* scratch, float* out) {
  LidarPoint* kept = reinterpret_cast<LidarPoint*>(scratch);
  float* fps_scratch = scratch + 4 * n;
  uint32_t* idx = reinterpret_cast<uint32_t*>(fps_scratch + 4 * n);
  std::memcpy(kept, pts, n * sizeof(LidarPoint));
  const size_t m = lidar_radius_crop__ref(kept, n, p.crop_radius_m);
  const size_t count = size_t(p.samples);
  LidarInputResult r;
  r.points = m;
  if (m == 0) {
    std::memset(out, 0, count * 6 * sizeof(float));
    r.enough = false;
    return r;
  }
  r.enough = fast ? lidar_fps(kept, m, count, idx, fps_scratch)
                  : lidar_fps__ref(kept, m, count, idx, fps_scratch);
  // The samples' mean in double, rounded once (lidar_points.py does the same).
  double sum[3] = {0, 0, 0};
  for (size_t i = 0; i < count; ++i) {
    sum[0] += kept[idx[i]].x;
    sum[1] += kept[idx[i]].y;
    sum[2] += kept[idx[i]].z;
  }
  const float c[3] = {float(sum[0] / double(count)), float(sum[1] / double(count)),
                      float(sum[2] / double(count))};
  const float s = p.coord_scale_m;
  for (size_t i = 0; i < count; ++i) {
    const LidarPoint& q = kept[idx[i]];
    const float v[3] = {q.x, q.y, q.z};
    float* o = out + 6 * i;
    for (int k = 0; k < 3; ++k) {
      o[k] = v[k] / s;
      o[3 + k] = (v[k] - c[k]) / s;
    }
    for (int k = 0; k < 6; ++k) o[k] = (o[k] - p.mean[k]) / p.std[k];
  }
  return r;
}

}  // namespace aprt::kernels
