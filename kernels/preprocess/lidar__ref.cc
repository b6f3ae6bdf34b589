#include "kernels/preprocess/lidar__ref.h"

#include <cmath>
#include <cstring>

#include "kernels/points/pointnet__ref.h"

namespace aprt::kernels {

void lidar_bev_histogram__ref(const LidarPoint* p, size_t n, const BevParams& b, float* out) {
  const size_t cells = size_t(b.grid) * b.grid * 2;
  for (size_t i = 0; i < cells; ++i) out[i] = 0.0f;
  for (size_t i = 0; i < n; ++i) {
    const double r = std::floor((double(p[i].x) - b.x_min) / b.cell_m);
    const double c = std::floor((double(p[i].y) - b.y_min) / b.cell_m);
    if (!(r >= 0 && r < b.grid && c >= 0 && c < b.grid)) continue;
    const int ch = p[i].z < b.height_threshold_m ? 0 : 1;
    out[(size_t(r) * b.grid + size_t(c)) * 2 + ch] += 1.0f;
  }
  for (size_t i = 0; i < cells; ++i) {
    out[i] = (out[i] < b.clip_count ? out[i] : b.clip_count) / b.clip_count;
  }
}

size_t lidar_radius_crop__ref(LidarPoint* p, size_t n, float radius) {
  size_t kept = 0;
  const float r2 = radius * radius;
  for (size_t i = 0; i < n; ++i) {
    if (p[i].x * p[i].x + p[i].y * p[i].y <= r2) p[kept++] = p[i];
  }
  return kept;
}

bool lidar_fps__ref(const LidarPoint* p, size_t n, size_t count, uint32_t* idx, float* dist) {
  if (count == 0) return n > 0;
  if (n == 0) {
    std::memset(idx, 0, count * sizeof(uint32_t));
    return false;
  }
  // The engine's FPS on rows of 4 floats (x y z intensity), then the padding.
  const size_t take = n < count ? n : count;
  f32_fps__ref(&p[0].x, 4, n, take, idx, dist);
  for (size_t s = take; s < count; ++s) idx[s] = idx[s - take];
  return n >= count;
}

}  // namespace aprt::kernels
