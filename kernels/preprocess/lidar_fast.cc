#include "kernels/preprocess/lidar_fast.h"

#include <cmath>
#include <cstring>

#include "kernels/points/pointnet_fast.h"

namespace aprt::kernels {

void lidar_bev_histogram(const LidarPoint* p, size_t n, const BevParams& b, uint16_t* counts,
                         float* out) {
  const size_t cells = size_t(b.grid) * b.grid * 2;
  std::memset(counts, 0, cells * sizeof(uint16_t));
  // Counting in integers, saturating at the clip (which is < 65536 in practice;
  // clip_count above it saturates at 65535 and still clips right).
  const uint32_t cap = b.clip_count < 65535.0f ? uint32_t(std::ceil(b.clip_count)) : 65535u;
  for (size_t i = 0; i < n; ++i) {
    // The reference's binning, to the bit: double division, floor.
    const double r = std::floor((double(p[i].x) - b.x_min) / b.cell_m);
    const double c = std::floor((double(p[i].y) - b.y_min) / b.cell_m);
    if (!(r >= 0 && r < b.grid && c >= 0 && c < b.grid)) continue;
    uint16_t& k =
        counts[(size_t(r) * b.grid + size_t(c)) * 2 + (p[i].z < b.height_threshold_m ? 0 : 1)];
    if (k < cap) ++k;
  }
  for (size_t i = 0; i < cells; ++i) {
    const float v = float(counts[i]);
    out[i] = (v < b.clip_count ? v : b.clip_count) / b.clip_count;
  }
}

bool lidar_fps(const LidarPoint* p, size_t n, size_t count, uint32_t* idx, float* scratch) {
  if (count == 0) return n > 0;
  if (n == 0) {
    std::memset(idx, 0, count * sizeof(uint32_t));
    return false;
  }
  // The engine's FPS (structure of arrays) on rows of 4 floats, then the padding.
  const size_t take = n < count ? n : count;
  f32_points_to_soa(&p[0].x, 4, n, scratch);
  f32_fps_soa(scratch, n, take, idx, scratch + 3 * n);
  for (size_t s = take; s < count; ++s) idx[s] = idx[s - take];
  return n >= count;
}

}  // namespace aprt::kernels
