// The AArch64 kernel table (NEON is part of the armv8-a baseline).
#include "kernels/common/kernel_set.h"

namespace aprt::kernels {

void f32_gemm_8x12__neon(const GemmArgs&, int, int, int, int);
void f32_dwconv2d__neon(const Conv2dShape&, const float*, const float*, const float*, Act, float*,
                        int, int);
void f32_conv2d__neon(const Conv2dShape&, const float*, const float*, const float*, const float*,
                      Act, float*, int, int);
void f32_layernorm__neon(int, const float*, const float*, const float*, float, float*, int, int);
void f32_add__neon(const float*, const float*, float*, size_t, size_t);
void f32_softmax__neon(int, float*, int, int);
void f32_cross_scores__neon(int, int, const float*, const float*, const float*, float*, size_t, int,
                            int);
void f32_activation__neon(Act, const float*, float*, size_t, size_t);
void f32_se_gate__neon(int, int, int, const float*, const float*, const float*, const float*,
                       const float*, float*, float*);
void f32_se_scale__neon(int, const float*, const float*, float*, int, int);
void f32_attention_pack_kv__neon(int, int, int, const float*, size_t, const float*, size_t, int,
                                 float*, float*);
bool f32_attention_3x4v__neon(int, int, int, const float*, size_t, const float*, const float*, int,
                              float, float*, size_t, int, int, float*);
size_t f32_attention_scratch__neon(int);
void u8_f32_preprocess__neon(const PreprocessPlan&, const ImageView&, float*);

namespace {

const KernelSet kNeon = {
    "neon",
    4,
    8,
    12,
    f32_gemm_8x12__neon,
    f32_dwconv2d__neon,
    f32_conv2d__neon,
    f32_layernorm__neon,
    f32_add__neon,
    f32_softmax__neon,
    f32_cross_scores__neon,
    f32_activation__neon,
    f32_se_gate__neon,
    f32_se_scale__neon,
    256,
    3,
    128,
    f32_attention_pack_kv__neon,
    f32_attention_3x4v__neon,
    f32_attention_scratch__neon,
    u8_f32_preprocess__neon,
};

}  // namespace

const KernelSet* kernel_set_avx512() {
  return nullptr;
}
const KernelSet* kernel_set_avx2() {
  return nullptr;
}
const KernelSet* kernel_set_neon() {
  return &kNeon;
}

}  // namespace aprt::kernels
