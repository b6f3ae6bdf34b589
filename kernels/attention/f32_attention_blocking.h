// The fused attention kernels' blocking, the same on every ISA (the kernel
// table's attn_max_rows and attn_key_block; f32_attention_impl.inl).
#pragma once

namespace aprt::kernels {

// Keys per softmax block: K and V are packed padded to a multiple of it.
inline constexpr int kAttentionKeyBlock = 128;
// The most query rows one attention block call takes (a chunk of row groups).
inline constexpr int kAttentionMaxRows = 256;

}  // namespace aprt::kernels
