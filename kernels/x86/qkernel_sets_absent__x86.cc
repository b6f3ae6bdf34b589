// The int8 tables an x86 build does not contain.
#include "kernels/common/qkernel_set.h"

namespace aprt::kernels {
const QKernelSet* qkernel_set_neondot() {
  return nullptr;
}
const QKernelSet* qkernel_set_neon() {
  return nullptr;
}
}  // namespace aprt::kernels
