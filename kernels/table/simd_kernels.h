// The fp32 kernels written once for every SIMD ISA (the `*__simd.cc` files of
// each family), declared for the ISA being compiled (kernels/simd/isa.h names
// them). Included by those files and by the ISA's table
// (kernels/table/f32_kernels__simd.cc), so a definition that drifts from its
// table entry does not compile.
#pragma once

#include "kernels/attention/f32_attention_blocking.h"
#include "kernels/common/kernel_types.h"
#include "kernels/gemm/f32_gemm.h"
#include "kernels/preprocess/preprocess_image.h"
#include "kernels/simd/isa.h"

namespace aprt::kernels {

// gemm/: C = act(A B + bias) + residual over row and panel ranges (GemmArgs).
void APRT_SIMD_NAME(f32_gemm_, APRT_GEMM_TILE)(const GemmArgs& g, int r0, int r1, int p0, int p1);
// conv/: output rows [oy0, oy1) of a dense convolution (weights packed by
// f32_conv2d_pack_weights).
void APRT_SIMD_NAME(f32_conv2d, )(const Conv2dShape& s, const float* x, const float* w_packed,
                                  const float* bias, const float* residual, Act act, float* y,
                                  int oy0, int oy1);
// dwconv/: output rows [oy0, oy1) of a depthwise convolution (weights [KH][KW][C]).
void APRT_SIMD_NAME(f32_dwconv2d, )(const Conv2dShape& s, const float* x, const float* w,
                                    const float* bias, Act act, float* y, int oy0, int oy1);
// rowwise/
void APRT_SIMD_NAME(f32_layernorm, )(int n, const float* x, const float* gamma, const float* beta,
                                     float eps, float* y, int r0, int r1);
void APRT_SIMD_NAME(f32_add, )(const float* a, const float* b, float* y, size_t i0, size_t i1);
void APRT_SIMD_NAME(f32_softmax, )(int n, float* x, int r0, int r1);
void APRT_SIMD_NAME(f32_activation, )(Act act, const float* x, float* y, size_t i0, size_t i1);
void APRT_SIMD_NAME(f32_se_gate, )(int pixels, int c, int cr, const float* x, const float* w1,
                                   const float* b1, const float* w2t, const float* b2, float* gate,
                                   float* scratch);
void APRT_SIMD_NAME(f32_se_scale, )(int c, const float* x, const float* gate, float* y, int p0,
                                    int p1);
// attention/
void APRT_SIMD_NAME(f32_cross_scores, )(int e, int heads, const float* m, const float* pos,
                                        const float* qt, float* s, size_t ls, int j0, int j1);
void APRT_SIMD_NAME(f32_attention_pack_kv, )(int kv_len, int lk_pad, int d, const float* k,
                                             size_t ldk, const float* v, size_t ldv, int h,
                                             float* kt, float* vp);
bool APRT_SIMD_NAME(f32_attention_, APRT_ATTN_TILE)(int rows, int kv_len, int d, const float* q,
                                                    size_t ldq, const float* kt, const float* vp,
                                                    int lk_pad, float scale, float* o, size_t ldo,
                                                    int h, int q0, float* scratch);
size_t APRT_SIMD_NAME(f32_attention_scratch, )(int d);
// preprocess/: a camera frame to the network input.
void APRT_SIMD_NAME(u8_f32_preprocess, )(const PreprocessPlan& plan, const ImageView& img,
                                         float* out);

}  // namespace aprt::kernels
