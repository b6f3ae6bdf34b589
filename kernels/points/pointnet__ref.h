// The PointNet++ operators of the raw-points modality (issue #5; DESIGN.md
// 4.3), scalar references. tools/aprt_tools/model/point_ops.py is their
// definition; the engine's ops (runtime/engine/ops/point_ops.cc) call these or
// their fast twins (kernels/points/pointnet_fast.h), which pick the same
// indices bit for bit.
//
// Points are rows of a row-major matrix: point i's x, y, z are
// xyz[i * stride + 0..2] (stride >= 3: the coordinates may be the first
// columns of a wider feature row). Squared distances are
// (dx*dx + dy*dy) + dz*dz in float32 with no fused multiply-add (these files
// are built with -ffp-contract=off); every tie goes to the lower index.
#pragma once

#include <cstddef>
#include <cstdint>

namespace aprt::kernels {

// Farthest-point sampling: idx[0] = 0, then the point farthest from all
// chosen so far. count <= n (the caller checks). dist: n floats.
void f32_fps__ref(const float* xyz, size_t stride, size_t n, size_t count, uint32_t* idx,
                  float* dist);

// Ball query and grouping of centres [c0, c1): for centre s, the first k
// points (index order) with d2 < radius * radius; fewer: the rest repeat the
// first found; none: point 0. y[s][j] = (p - centre) ++ feats[p] (c_feat
// floats per point; feats may be null with c_feat 0): [S][k][3 + c_feat].
void f32_ball_group__ref(const float* xyz, size_t stride, size_t n, const float* centres,
                         size_t c_stride, int c0, int c1, float radius, int k, const float* feats,
                         int c_feat, float* y);

// y[s][c] = max over j < k of x[s][j][c], for s in [s0, s1).
void f32_group_max__ref(int k, int c, const float* x, float* y, int s0, int s1);

// Inverse-distance interpolation for targets [t0, t1): the 3 known points with
// the smallest d2 (lowest index on ties; n_known >= 3), weights 1 / (d2 + 1e-8)
// over their sum, y[t] = sum of weight * feats[known] (c floats each).
void f32_three_interp__ref(const float* targets, size_t t_stride, int t0, int t1,
                           const float* known, size_t k_stride, size_t n_known, const float* feats,
                           int c, float* y);

// Height-grouped grid tokens: points stably sorted by z and cut into `groups`
// equal groups, each stably sorted by x into gx slabs, each stably sorted by
// y into gy cells; y[token][c] = max over the cell's points of feats[p][c],
// token = (group * gx + slab) * gy + cell. n % (groups gx gy) == 0.
// scratch: 4 * n floats (the sort's keys and indices).
void f32_grid_tokens__ref(const float* xyz, size_t stride, size_t n, int groups, int gx, int gy,
                          const float* feats, int c, float* y, float* scratch);

}  // namespace aprt::kernels
