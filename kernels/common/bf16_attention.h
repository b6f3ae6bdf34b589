// bf16 attention kernels (issue #4; FORMAT.md "bf16 attention"; the
// arithmetic in kernels/ref/bf16_attention__ref.h): one table per ISA that
// has a bf16 dot-product instruction, chosen once at load beside KernelSet
// and QKernelSet. AVX-512 BF16's vdpbf16ps multiplies two bf16 pairs per
// fp32 lane, so Q K^T and P V take half the instructions of the fp32 FMAs.
// Where no table runs (AVX2, NEON, AVX-512 without BF16), the op rounds Q, K
// and V to bf16 and runs the fp32 kernel over them (the weights then stay
// fp32: a little more accurate than this table, never less).
#pragma once

#include <cstddef>
#include <cstdint>

namespace aprt::kernels {

struct Bf16AttentionKernels {
  const char* isa;  // "avx512bf16"
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

// The table this build contains, or null (not compiled for this target).
const Bf16AttentionKernels* bf16_attention_avx512bf16();

}  // namespace aprt::kernels
