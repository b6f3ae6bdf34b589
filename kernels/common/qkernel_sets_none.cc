// A build for a CPU without fast int8 kernels: the reference ones only.
#include "kernels/common/bf16_attention.h"
#include "kernels/common/qkernel_set.h"

namespace aprt::kernels {
const QKernelSet* qkernel_set_avx512vnni() {
  return nullptr;
}
const QKernelSet* qkernel_set_avx2() {
  return nullptr;
}
const QKernelSet* qkernel_set_neondot() {
  return nullptr;
}
const QKernelSet* qkernel_set_neon() {
  return nullptr;
}
const Bf16AttentionKernels* bf16_attention_avx512bf16() {
  return nullptr;
}
}  // namespace aprt::kernels
