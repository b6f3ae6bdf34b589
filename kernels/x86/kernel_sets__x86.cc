// The x86 kernel tables. Compiled for the baseline ISA: it only takes
// addresses; each kernel lives in its own ISA-flagged translation unit.
#include "kernels/common/kernel_set.h"

namespace aprt::kernels {

void f32_gemm_8x32__avx512(const GemmArgs&, int, int, int, int);
void f32_dwconv2d__avx512(const Conv2dShape&, const float*, const float*, const float*, Act, float*,
                          int, int);
void f32_conv2d__avx512(const Conv2dShape&, const float*, const float*, const float*, const float*,
                        Act, float*, int, int);
void f32_layernorm__avx512(int, const float*, const float*, const float*, float, float*, int, int);
void f32_add__avx512(const float*, const float*, float*, size_t, size_t);
void f32_activation__avx512(Act, const float*, float*, size_t, size_t);
void f32_softmax__avx512(int, float*, int, int);
void f32_cross_scores__avx512(int, int, const float*, const float*, const float*, float*, size_t,
                              int, int);
void f32_se_gate__avx512(int, int, int, const float*, const float*, const float*, const float*,
                         const float*, float*, float*);
void f32_se_scale__avx512(int, const float*, const float*, float*, int, int);
void f32_attention_pack_kv__avx512(int, int, int, const float*, size_t, const float*, size_t, int,
                                   float*, float*);
bool f32_attention_8x2v__avx512(int, int, int, const float*, size_t, const float*, const float*,
                                int, float, float*, size_t, int, int, float*);
size_t f32_attention_scratch__avx512(int);

void f32_gemm_6x16__avx2(const GemmArgs&, int, int, int, int);
void f32_dwconv2d__avx2(const Conv2dShape&, const float*, const float*, const float*, Act, float*,
                        int, int);
void f32_conv2d__avx2(const Conv2dShape&, const float*, const float*, const float*, const float*,
                      Act, float*, int, int);
void f32_layernorm__avx2(int, const float*, const float*, const float*, float, float*, int, int);
void f32_add__avx2(const float*, const float*, float*, size_t, size_t);
void f32_activation__avx2(Act, const float*, float*, size_t, size_t);
void f32_softmax__avx2(int, float*, int, int);
void f32_cross_scores__avx2(int, int, const float*, const float*, const float*, float*, size_t, int,
                            int);
void f32_se_gate__avx2(int, int, int, const float*, const float*, const float*, const float*,
                       const float*, float*, float*);
void f32_se_scale__avx2(int, const float*, const float*, float*, int, int);
void f32_attention_pack_kv__avx2(int, int, int, const float*, size_t, const float*, size_t, int,
                                 float*, float*);
bool f32_attention_4x2v__avx2(int, int, int, const float*, size_t, const float*, const float*, int,
                              float, float*, size_t, int, int, float*);
size_t f32_attention_scratch__avx2(int);
void u8_f32_preprocess__avx512(const PreprocessPlan&, const ImageView&, float*);
void u8_f32_preprocess__avx2(const PreprocessPlan&, const ImageView&, float*);

namespace {

const KernelSet kAvx512 = {
    "avx512",
    16,
    8,
    32,
    f32_gemm_8x32__avx512,
    f32_dwconv2d__avx512,
    f32_conv2d__avx512,
    f32_layernorm__avx512,
    f32_add__avx512,
    f32_softmax__avx512,
    f32_cross_scores__avx512,
    f32_activation__avx512,
    f32_se_gate__avx512,
    f32_se_scale__avx512,
    256,
    8,
    128,
    f32_attention_pack_kv__avx512,
    f32_attention_8x2v__avx512,
    f32_attention_scratch__avx512,
    u8_f32_preprocess__avx512,
};

const KernelSet kAvx2 = {
    "avx2",
    8,
    6,
    16,
    f32_gemm_6x16__avx2,
    f32_dwconv2d__avx2,
    f32_conv2d__avx2,
    f32_layernorm__avx2,
    f32_add__avx2,
    f32_softmax__avx2,
    f32_cross_scores__avx2,
    f32_activation__avx2,
    f32_se_gate__avx2,
    f32_se_scale__avx2,
    256,
    4,
    128,
    f32_attention_pack_kv__avx2,
    f32_attention_4x2v__avx2,
    f32_attention_scratch__avx2,
    u8_f32_preprocess__avx2,
};

}  // namespace

const KernelSet* kernel_set_avx512() {
  return &kAvx512;
}
const KernelSet* kernel_set_avx2() {
  return &kAvx2;
}
const KernelSet* kernel_set_neon() {
  return nullptr;
}

}  // namespace aprt::kernels
