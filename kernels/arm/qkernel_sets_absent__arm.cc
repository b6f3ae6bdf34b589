// The int8 and bf16 tables an aarch64 build does not contain.
#include "kernels/common/bf16_attention.h"
#include "kernels/common/qkernel_set.h"

namespace aprt::kernels {
const QKernelSet* qkernel_set_avx512vnni() {
  return nullptr;
}
const QKernelSet* qkernel_set_avx2() {
  return nullptr;
}
const Bf16AttentionKernels* bf16_attention_avx512bf16() {
  return nullptr;
}
}  // namespace aprt::kernels
