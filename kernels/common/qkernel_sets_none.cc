// A build for a CPU without fast int8 kernels: the reference ones only.
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
}  // namespace aprt::kernels
