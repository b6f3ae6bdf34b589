// The PointNet++ operators, fast (issue #5): each equals its reference in
// kernels/points/pointnet__ref.h exactly -- the same indices, the same values.
// Portable C++ for the compiler's vectoriser like kernels/preprocess/lidar_fast.h
// (structure-of-arrays coordinates, distances in blocks, branch-free inner
// loops), built with -O3 -ffp-contract=off so distances round as the
// reference's do. The grid tokenisation has no fast twin: it sorts 1024
// points (~0.1 % of the model's time) and the reference is what runs.
#pragma once

#include <cstddef>
#include <cstdint>

namespace aprt::kernels {

// Coordinates rows -> structure of arrays soa[0..n) x, [n..2n) y, [2n..3n) z.
void f32_points_to_soa(const float* xyz, size_t stride, size_t n, float* soa);

// f32_fps__ref on coordinates already in soa (3 n floats); dist: n floats.
void f32_fps_soa(const float* soa, size_t n, size_t count, uint32_t* idx, float* dist);

// f32_ball_group__ref with the points in soa (3 n floats, from f32_points_to_soa).
void f32_ball_group_soa(const float* soa, size_t n, const float* centres, size_t c_stride, int c0,
                        int c1, float radius, int k, const float* feats, int c_feat, float* y);

// f32_group_max__ref.
void f32_group_max(int k, int c, const float* x, float* y, int s0, int s1);

// f32_three_interp__ref with the known points in soa (3 n_known floats);
// dist: n_known floats of per-thread scratch.
void f32_three_interp_soa(const float* targets, size_t t_stride, int t0, int t1, const float* soa,
                          size_t n_known, const float* feats, int c, float* y, float* dist);

}  // namespace aprt::kernels
