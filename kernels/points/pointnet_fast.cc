#include "kernels/points/pointnet_fast.h"

#include <cmath>
#include <cstring>

namespace aprt::kernels {
namespace {

constexpr size_t kBlock = 64;  // distances computed per vector sweep

// d[i] = (dx*dx + dy*dy) + dz*dz for points [i0, i0 + m) of soa (m <= kBlock).
inline void block_dist(const float* __restrict xs, const float* __restrict ys,
                       const float* __restrict zs, size_t i0, size_t m, float cx, float cy,
                       float cz, float* __restrict d) {
#if !defined(__clang__)
#pragma omp simd
#endif
  for (size_t i = 0; i < m; ++i) {
    const float dx = xs[i0 + i] - cx, dy = ys[i0 + i] - cy, dz = zs[i0 + i] - cz;
    d[i] = (dx * dx + dy * dy) + dz * dz;
  }
}

}  // namespace

void f32_points_to_soa(const float* xyz, size_t stride, size_t n, float* soa) {
  for (size_t i = 0; i < n; ++i) {
    soa[i] = xyz[i * stride];
    soa[n + i] = xyz[i * stride + 1];
    soa[2 * n + i] = xyz[i * stride + 2];
  }
}

void f32_fps_soa(const float* soa, size_t n, size_t count, uint32_t* idx, float* dist) {
  if (count == 0 || n == 0) return;
  const float* __restrict xs = soa;
  const float* __restrict ys = soa + n;
  const float* __restrict zs = soa + 2 * n;
  float* __restrict dd = dist;
  for (size_t i = 0; i < n; ++i) dd[i] = INFINITY;
  uint32_t last = 0;
  idx[0] = 0;
  for (size_t s = 1; s < count; ++s) {
    const float cx = xs[last], cy = ys[last], cz = zs[last];
    float best = -1.0f;
    // min and max are exact: the vector reduction's order does not matter.
#if !defined(__clang__)
#pragma omp simd reduction(max : best)
#endif
    for (size_t i = 0; i < n; ++i) {
      const float dx = xs[i] - cx, dy = ys[i] - cy, dz = zs[i] - cz;
      const float d = (dx * dx + dy * dy) + dz * dz;
      const float m = d < dd[i] ? d : dd[i];
      dd[i] = m;
      best = m > best ? m : best;
    }
    size_t arg = 0;  // the first index holding the maximum: the reference's tie rule
    while (dd[arg] != best) ++arg;
    idx[s] = last = uint32_t(arg);
  }
}

void f32_ball_group_soa(const float* soa, size_t n, const float* centres, size_t c_stride, int c0,
                        int c1, float radius, int k, const float* feats, int c_feat, float* y) {
  const float r2 = radius * radius;
  const size_t row = size_t(3 + c_feat);
  const float* xs = soa;
  const float* ys = soa + n;
  const float* zs = soa + 2 * n;
  alignas(64) float d[kBlock];
  for (int s = c0; s < c1; ++s) {
    const float* c = centres + size_t(s) * c_stride;
    float* out = y + size_t(s) * size_t(k) * row;
    int found = 0;
    // Blocks of distances, then the block's hits in index order; stops at k
    // (bounded by n per centre).
    for (size_t i0 = 0; i0 < n && found < k; i0 += kBlock) {
      const size_t m = n - i0 < kBlock ? n - i0 : kBlock;
      block_dist(xs, ys, zs, i0, m, c[0], c[1], c[2], d);
      // Most blocks hold no neighbour of a small ball: a vector count skips them.
      int hits = 0;
#if !defined(__clang__)
#pragma omp simd reduction(+ : hits)
#endif
      for (size_t i = 0; i < m; ++i) hits += d[i] < r2 ? 1 : 0;
      if (hits == 0) continue;
      for (size_t i = 0; i < m && found < k; ++i) {
        if (!(d[i] < r2)) continue;
        const size_t p = i0 + i;
        float* o = out + size_t(found) * row;
        o[0] = xs[p] - c[0];
        o[1] = ys[p] - c[1];
        o[2] = zs[p] - c[2];
        if (c_feat) std::memcpy(o + 3, feats + p * size_t(c_feat), size_t(c_feat) * sizeof(float));
        ++found;
      }
    }
    if (found == 0) {
      out[0] = xs[0] - c[0];
      out[1] = ys[0] - c[1];
      out[2] = zs[0] - c[2];
      if (c_feat) std::memcpy(out + 3, feats, size_t(c_feat) * sizeof(float));
      found = 1;
    }
    for (int j = found; j < k; ++j) std::memcpy(out + size_t(j) * row, out, row * sizeof(float));
  }
}

void f32_group_max(int k, int c, const float* x, float* y, int s0, int s1) {
  // 64 channels at a time, their maxima kept in registers across the k rows.
  constexpr int kTile = 64;
  for (int s = s0; s < s1; ++s) {
    const float* __restrict g = x + size_t(s) * size_t(k) * size_t(c);
    float* __restrict o = y + size_t(s) * size_t(c);
    for (int f0 = 0; f0 < c; f0 += kTile) {
      const int w = c - f0 < kTile ? c - f0 : kTile;
      alignas(64) float acc[kTile];
      for (int f = 0; f < w; ++f) acc[f] = g[f0 + f];
      for (int j = 1; j < k; ++j) {
        const float* __restrict r = g + size_t(j) * size_t(c) + f0;
#if !defined(__clang__)
#pragma omp simd
#endif
        for (int f = 0; f < w; ++f) acc[f] = acc[f] < r[f] ? r[f] : acc[f];
      }
      for (int f = 0; f < w; ++f) o[f0 + f] = acc[f];
    }
  }
}

void f32_three_interp_soa(const float* targets, size_t t_stride, int t0, int t1, const float* soa,
                          size_t n_known, const float* feats, int c, float* y, float* dist) {
  const float* xs = soa;
  const float* ys = soa + n_known;
  const float* zs = soa + 2 * n_known;
  for (int t = t0; t < t1; ++t) {
    const float* p = targets + size_t(t) * t_stride;
    for (size_t i0 = 0; i0 < n_known; i0 += kBlock) {
      const size_t m = n_known - i0 < kBlock ? n_known - i0 : kBlock;
      block_dist(xs, ys, zs, i0, m, p[0], p[1], p[2], dist + i0);
    }
    float d[3] = {INFINITY, INFINITY, INFINITY};
    uint32_t id[3] = {0, 0, 0};
    for (size_t i = 0; i < n_known; ++i) {
      const float v = dist[i];
      if (!(v < d[2])) continue;
      int at = 2;
      while (at > 0 && v < d[at - 1]) {
        d[at] = d[at - 1];
        id[at] = id[at - 1];
        --at;
      }
      d[at] = v;
      id[at] = uint32_t(i);
    }
    const float r0 = 1.0f / (d[0] + 1e-8f), r1 = 1.0f / (d[1] + 1e-8f), r2 = 1.0f / (d[2] + 1e-8f);
    const float norm = (r0 + r1) + r2;
    const float w0 = r0 / norm, w1 = r1 / norm, w2 = r2 / norm;
    const float* __restrict f0 = feats + size_t(id[0]) * size_t(c);
    const float* __restrict f1 = feats + size_t(id[1]) * size_t(c);
    const float* __restrict f2 = feats + size_t(id[2]) * size_t(c);
    float* __restrict o = y + size_t(t) * size_t(c);
#if !defined(__clang__)
#pragma omp simd
#endif
    for (int f = 0; f < c; ++f) o[f] = (w0 * f0[f] + w1 * f1[f]) + w2 * f2[f];
  }
}

}  // namespace aprt::kernels
