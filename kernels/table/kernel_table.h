// The kernel table: one ISA's fast kernels as function pointers, in three
// parts -- fp32 (every ISA), int8 and bf16 attention (where the CPU has the
// instructions) -- chosen once at Engine::load() by pick_kernels() from what
// the CPU reports. Ops store the functions they need at prepare; nothing on
// the run path asks about the CPU again. Every function has a reference twin
// in its family's folder and a randomised differential test
// (tests/kernels/<family>/).
//
// The parts of each ISA are written with designated initialisers in one place
// each: kernels/table/f32_kernels__simd.cc (the fp32 part, one list compiled
// per ISA), the int8 GEMM files (kernels/gemm/qu8s8_gemm_*), the bf16
// attention file; kernels/table/kernel_table.cc lists which parts go together.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "kernels/common/kernel_types.h"
#include "kernels/dwconv/qu8s8_dwconv2d.h"
#include "kernels/gemm/f32_gemm.h"
#include "kernels/gemm/qs8_gemm.h"
#include "kernels/preprocess/preprocess_image.h"
#include "kernels/table/cpu_features.h"
#include "runtime/base/expected.h"

namespace aprt::kernels {

struct KernelSet {  // the fp32 part: every ISA has one
  const char* isa;  // "avx512", "avx2", "neon", ...
  int lanes;        // floats per vector register
  int gemm_mr;      // rows per GEMM tile
  int gemm_nr;      // columns per packed weight panel (f32_pack_b's nr)
  // C rows [r0, r1) x column panels [p0, p1) of a GemmArgs product.
  void (*gemm)(const GemmArgs& g, int r0, int r1, int p0, int p1);
  // Output rows [oy0, oy1) of a depthwise convolution (weights [KH][KW][C]).
  void (*dwconv_rows)(const Conv2dShape& s, const float* x, const float* w, const float* bias,
                      Act act, float* y, int oy0, int oy1);
  // Output rows [oy0, oy1) of a dense convolution; weights packed by
  // f32_conv2d_pack_weights ([KH][KW][Ci][Co]).
  void (*conv_rows)(const Conv2dShape& s, const float* x, const float* w_packed, const float* bias,
                    const float* residual, Act act, float* y, int oy0, int oy1);
  void (*layernorm_rows)(int n, const float* x, const float* gamma, const float* beta, float eps,
                         float* y, int r0, int r1);
  void (*add)(const float* a, const float* b, float* y, size_t i0, size_t i1);
  // In-place softmax of rows [r0, r1) of an [rows][n] matrix.
  void (*softmax_rows)(int n, float* x, int r0, int r1);
  // Single-query attention scores s[h * ls + j] = qt_h . (m_j + pos_j) of
  // memory rows [j0, j1) (pos may be null; kernels/attention/f32_cross_attention_1q__ref.h).
  void (*cross_scores)(int e, int heads, const float* m, const float* pos, const float* qt,
                       float* s, size_t ls, int j0, int j1);
  void (*activation)(Act act, const float* x, float* y, size_t i0, size_t i1);
  // Squeeze-excite: the per-channel gate (W2 transposed: [Cr][C]); scratch C + Cr floats.
  void (*se_gate)(int pixels, int c, int cr, const float* x, const float* w1, const float* b1,
                  const float* w2t, const float* b2, float* gate, float* scratch);
  void (*se_scale)(int c, const float* x, const float* gate, float* y, int p0, int p1);
  // Attention: the most query rows one attn_block call takes, its row-group
  // size, and keys per block (K and V are packed padded to a multiple of it:
  // lk_pad floats per head dimension).
  int attn_max_rows;
  int attn_group_rows;
  int attn_key_block;
  // Packs head h of K and V ([L][E] rows) into kt and vp (E * lk_pad floats each).
  void (*attn_pack_kv)(int kv_len, int lk_pad, int d, const float* k, size_t ldk, const float* v,
                       size_t ldv, int h, float* kt, float* vp);
  // false: head width unsupported here (use the reference kernel).
  bool (*attn_block)(int rows, int kv_len, int d, const float* q, size_t ldq, const float* kt,
                     const float* vp, int lk_pad, float scale, float* o, size_t ldo, int h, int q0,
                     float* scratch);
  size_t (*attn_scratch)(int d);  // per-thread floats for attn_block
  // A camera frame to the network input (kernels/preprocess/preprocess_image.h).
  void (*preprocess)(const PreprocessPlan& plan, const ImageView& img, float* out);
};

struct QKernelSet {  // the int8 part
  const char* isa;   // "avx512vnni", "avx2", "neondot", "neon"
  int mr, nr, kgroup;
  // C rows [r0, r1) x column panels [p0, p1) (panels of nr columns).
  void (*gemm)(const QGemmArgs& g, int r0, int r1, int p0, int p1);
  // q[i] = clamp(round_half_even(x[i] * inv_scale) + zero, 0, 255).
  void (*quantize)(size_t n, const float* x, float inv_scale, int32_t zero, uint8_t* q);
  // Output rows [oy0, oy1) of an int8 depthwise convolution.
  void (*dwconv_rows)(const QDwConvArgs& a, int oy0, int oy1);
  // Attention with int8 scores (kernels/attention/qs8_attention.h), null where
  // this table has none (the op then fake-quantises Q and K and runs the fp32
  // kernel). Like KernelSet's attention: the most query rows per call, the
  // row-group size, keys per block; the packed K of all heads (attn_kq_bytes)
  // and V (fp32, E * lk_pad floats); per-thread scratch floats.
  int attn_max_rows = 0, attn_group_rows = 0, attn_key_block = 0;
  size_t (*attn_kq_bytes)(int heads, int lk_pad, int d) = nullptr;
  void (*attn_pack_kv)(int kv_len, int lk_pad, int d, const float* k, size_t ldk, const float* v,
                       size_t ldv, int h, uint8_t* kq, float* vp) = nullptr;
  bool (*attn_block)(int rows, int kv_len, int d, const float* q, size_t ldq, const uint8_t* kq,
                     const float* vp, int lk_pad, float scale, float* o, size_t ldo, int h, int q0,
                     float* scratch) = nullptr;
  size_t (*attn_scratch)(int d) = nullptr;
};

struct Bf16AttentionKernels {  // the bf16 part
  const char* isa;             // "avx512bf16"
  // As KernelSet's attention: the most query rows per call, the row-group
  // size, keys per block (lk_pad is a multiple of it).
  int max_rows, group_rows, key_block;
  // Packed K and V of all heads (pack_kv writes head h of them).
  size_t (*kv_bytes)(int heads, int lk_pad, int d);
  void (*pack_kv)(int kv_len, int lk_pad, int d, const float* k, size_t ldk, const float* v,
                  size_t ldv, int h, uint16_t* kv);
  // Query rows [q0, q0 + rows) of head h; false if d is odd or wider than 128.
  bool (*block)(int rows, int kv_len, int d, const float* q, size_t ldq, const uint16_t* kv,
                int lk_pad, float scale, float* o, size_t ldo, int h, int q0, float* scratch);
  size_t (*scratch)(int d);  // per-thread floats for block
};

// One ISA's table: its fp32 part and the int8 / bf16 parts that go with it on
// this CPU. A null part means the portable reference kernels for that part
// (a null f32 part: the whole table is the reference).
struct KernelTable {
  const KernelSet* f32 = nullptr;
  const QKernelSet* qs8 = nullptr;
  const Bf16AttentionKernels* bf16 = nullptr;
  const char* name() const { return f32 ? f32->isa : "ref"; }
};

// The one picker. `isa`: null, "" or "auto" picks the best table this CPU
// runs; "ref" the portable reference kernels; "avx512", "avx2", "neon" force
// one, and fail with a clear message if this build lacks it or this CPU cannot
// run it (never a SIGILL later). With an fp32 part it adds the best int8 part
// that goes with it (AVX-512 VNNI, else AVX2, beside AVX-512; AVX2 beside
// AVX2; NEON dotprod, else plain NEON, beside NEON) and the bf16 attention
// part where the CPU has AVX-512 BF16.
Expected<KernelTable> pick_kernels(const char* isa);

// Every ISA this build contains, best first: its fp32 part and the int8 and
// bf16 parts that may go with it, each with whether this CPU runs it. For
// tests and benchmarks that run every part against the reference.
struct IsaParts {
  const char* isa;
  const KernelSet* f32;
  bool f32_runs;
  const QKernelSet* qs8[2];  // preference order; null entries unused
  bool qs8_runs[2];
  const Bf16AttentionKernels* bf16;
  bool bf16_runs;
};
std::span<const IsaParts> isa_parts();

// Dense convolution weights [Co][KH][KW][Ci] -> [KH][KW][Ci][Co].
void f32_conv2d_pack_weights(int co, int kh, int kw, int ci, const float* w, float* out);

}  // namespace aprt::kernels
