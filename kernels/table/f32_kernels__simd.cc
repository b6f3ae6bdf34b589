// The fp32 part of the kernel table, one list for every SIMD ISA: compiled
// once per ISA (kernels/simd/isa.h), it defines f32_kernels__avx512,
// f32_kernels__avx2 or f32_kernels__neon from that ISA's kernels.
#include "kernels/table/kernel_table.h"
#include "kernels/table/simd_kernels.h"

namespace aprt::kernels {

extern const KernelSet APRT_SIMD_NAME(f32_kernels, );
const KernelSet APRT_SIMD_NAME(f32_kernels, ) = {
    .isa = APRT_SIMD_ISA_NAME,
    .lanes = APRT_SIMD_LANES,
    .gemm_mr = APRT_GEMM_MR,
    .gemm_nr = APRT_GEMM_NV * APRT_SIMD_LANES,
    .gemm = APRT_SIMD_NAME(f32_gemm_, APRT_GEMM_TILE),
    .dwconv_rows = APRT_SIMD_NAME(f32_dwconv2d, ),
    .conv_rows = APRT_SIMD_NAME(f32_conv2d, ),
    .layernorm_rows = APRT_SIMD_NAME(f32_layernorm, ),
    .add = APRT_SIMD_NAME(f32_add, ),
    .softmax_rows = APRT_SIMD_NAME(f32_softmax, ),
    .cross_scores = APRT_SIMD_NAME(f32_cross_scores, ),
    .activation = APRT_SIMD_NAME(f32_activation, ),
    .se_gate = APRT_SIMD_NAME(f32_se_gate, ),
    .se_scale = APRT_SIMD_NAME(f32_se_scale, ),
    .attn_max_rows = kAttentionMaxRows,
    .attn_group_rows = APRT_ATTN_ROWS,
    .attn_key_block = kAttentionKeyBlock,
    .attn_pack_kv = APRT_SIMD_NAME(f32_attention_pack_kv, ),
    .attn_block = APRT_SIMD_NAME(f32_attention_, APRT_ATTN_TILE),
    .attn_scratch = APRT_SIMD_NAME(f32_attention_scratch, ),
    .preprocess = APRT_SIMD_NAME(u8_f32_preprocess, ),
};

}  // namespace aprt::kernels
