#include "kernels/points/pointnet__ref.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace aprt::kernels {
namespace {

inline float sq_dist(const float* a, const float* b) {
  const float dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return (dx * dx + dy * dy) + dz * dz;
}

// A float as an unsigned key with the same order (-0 and +0 equal, NaN after
// +inf): a total order, so the sort below is well defined whatever arrives.
inline uint32_t order_key(float f) {
  f += 0.0f;  // -0 -> +0
  uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

// Stable sort of idx[0..m) by coord[idx * stride]: (key, position) pairs in
// one 64-bit word each, sorted; keys: m uint64, tmp: m uint32.
void stable_sort_by(const float* xyz, size_t stride, int axis, uint32_t* idx, size_t m,
                    uint64_t* keys, uint32_t* tmp) {
  for (size_t p = 0; p < m; ++p) {
    keys[p] = uint64_t(order_key(xyz[idx[p] * stride + axis])) << 32 | uint32_t(p);
  }
  std::sort(keys, keys + m);
  for (size_t p = 0; p < m; ++p) tmp[p] = idx[uint32_t(keys[p])];
  std::memcpy(idx, tmp, m * sizeof(uint32_t));
}

}  // namespace

void f32_fps__ref(const float* xyz, size_t stride, size_t n, size_t count, uint32_t* idx,
                  float* dist) {
  if (count == 0 || n == 0) return;
  for (size_t i = 0; i < n; ++i) dist[i] = INFINITY;
  uint32_t last = 0;
  idx[0] = 0;
  for (size_t s = 1; s < count; ++s) {
    const float* c = xyz + size_t(last) * stride;
    float best = -1.0f;
    uint32_t arg = 0;
    for (size_t i = 0; i < n; ++i) {
      const float d = sq_dist(xyz + i * stride, c);
      if (d < dist[i]) dist[i] = d;
      if (dist[i] > best) {
        best = dist[i];
        arg = uint32_t(i);
      }
    }
    idx[s] = last = arg;
  }
}

void f32_ball_group__ref(const float* xyz, size_t stride, size_t n, const float* centres,
                         size_t c_stride, int c0, int c1, float radius, int k, const float* feats,
                         int c_feat, float* y) {
  const float r2 = radius * radius;
  const size_t row = size_t(3 + c_feat);
  for (int s = c0; s < c1; ++s) {
    const float* c = centres + size_t(s) * c_stride;
    float* out = y + size_t(s) * size_t(k) * row;
    int found = 0;
    for (size_t i = 0; i < n && found < k; ++i) {
      if (!(sq_dist(xyz + i * stride, c) < r2)) continue;
      float* o = out + size_t(found) * row;
      const float* p = xyz + i * stride;
      o[0] = p[0] - c[0];
      o[1] = p[1] - c[1];
      o[2] = p[2] - c[2];
      for (int f = 0; f < c_feat; ++f) o[3 + f] = feats[i * size_t(c_feat) + f];
      ++found;
    }
    if (found == 0) {  // cannot happen for centres sampled from the points: point 0
      const float* p = xyz;
      out[0] = p[0] - c[0];
      out[1] = p[1] - c[1];
      out[2] = p[2] - c[2];
      for (int f = 0; f < c_feat; ++f) out[3 + f] = feats[f];
      found = 1;
    }
    for (int j = found; j < k; ++j) std::memcpy(out + size_t(j) * row, out, row * sizeof(float));
  }
}

void f32_group_max__ref(int k, int c, const float* x, float* y, int s0, int s1) {
  for (int s = s0; s < s1; ++s) {
    const float* g = x + size_t(s) * size_t(k) * size_t(c);
    float* o = y + size_t(s) * size_t(c);
    for (int f = 0; f < c; ++f) o[f] = g[f];
    for (int j = 1; j < k; ++j) {
      for (int f = 0; f < c; ++f) o[f] = std::max(o[f], g[size_t(j) * size_t(c) + f]);
    }
  }
}

void f32_three_interp__ref(const float* targets, size_t t_stride, int t0, int t1,
                           const float* known, size_t k_stride, size_t n_known, const float* feats,
                           int c, float* y) {
  for (int t = t0; t < t1; ++t) {
    const float* p = targets + size_t(t) * t_stride;
    // The three smallest (d2, index), ascending; scanning in index order with a
    // strict comparison keeps the lower index ahead on ties.
    float d[3] = {INFINITY, INFINITY, INFINITY};
    uint32_t id[3] = {0, 0, 0};
    for (size_t i = 0; i < n_known; ++i) {
      const float v = sq_dist(known + i * k_stride, p);
      if (v < d[2]) {
        int at = 2;
        while (at > 0 && v < d[at - 1]) {
          d[at] = d[at - 1];
          id[at] = id[at - 1];
          --at;
        }
        d[at] = v;
        id[at] = uint32_t(i);
      }
    }
    const float r0 = 1.0f / (d[0] + 1e-8f), r1 = 1.0f / (d[1] + 1e-8f), r2 = 1.0f / (d[2] + 1e-8f);
    const float norm = (r0 + r1) + r2;
    const float w0 = r0 / norm, w1 = r1 / norm, w2 = r2 / norm;
    const float* f0 = feats + size_t(id[0]) * size_t(c);
    const float* f1 = feats + size_t(id[1]) * size_t(c);
    const float* f2 = feats + size_t(id[2]) * size_t(c);
    float* o = y + size_t(t) * size_t(c);
    for (int f = 0; f < c; ++f) o[f] = (w0 * f0[f] + w1 * f1[f]) + w2 * f2[f];
  }
}

void f32_grid_tokens__ref(const float* xyz, size_t stride, size_t n, int groups, int gx, int gy,
                          const float* feats, int c, float* y, float* scratch) {
  uint64_t* keys = reinterpret_cast<uint64_t*>(scratch);
  uint32_t* idx = reinterpret_cast<uint32_t*>(scratch + 2 * n);
  uint32_t* tmp = idx + n;
  for (size_t i = 0; i < n; ++i) idx[i] = uint32_t(i);
  stable_sort_by(xyz, stride, 2, idx, n, keys, tmp);
  const size_t per_group = n / size_t(groups), per_slab = per_group / size_t(gx);
  const size_t per_cell = per_slab / size_t(gy);
  for (int g = 0; g < groups; ++g) {
    uint32_t* gi = idx + size_t(g) * per_group;
    stable_sort_by(xyz, stride, 0, gi, per_group, keys, tmp);
    for (int sx = 0; sx < gx; ++sx) {
      uint32_t* si = gi + size_t(sx) * per_slab;
      stable_sort_by(xyz, stride, 1, si, per_slab, keys, tmp);
      for (int sy = 0; sy < gy; ++sy) {
        const uint32_t* ci = si + size_t(sy) * per_cell;
        float* o = y + size_t((g * gx + sx) * gy + sy) * size_t(c);
        for (int f = 0; f < c; ++f) o[f] = feats[size_t(ci[0]) * size_t(c) + f];
        for (size_t j = 1; j < per_cell; ++j) {
          const float* fp = feats + size_t(ci[j]) * size_t(c);
          for (int f = 0; f < c; ++f) o[f] = std::max(o[f], fp[f]);
        }
      }
    }
  }
}

}  // namespace aprt::kernels
