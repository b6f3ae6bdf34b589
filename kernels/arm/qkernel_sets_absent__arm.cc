// The int8 tables an aarch64 build does not contain.
#include "kernels/common/qkernel_set.h"

namespace aprt::kernels {
const QKernelSet* qkernel_set_avx512vnni() {
  return nullptr;
}
const QKernelSet* qkernel_set_avx2() {
  return nullptr;
}
}  // namespace aprt::kernels
