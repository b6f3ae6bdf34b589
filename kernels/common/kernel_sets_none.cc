// Architectures without fast kernels: the engine runs the reference kernels.
#include "kernels/common/kernel_set.h"

namespace aprt::kernels {

const KernelSet* kernel_set_avx512() {
  return nullptr;
}
const KernelSet* kernel_set_avx2() {
  return nullptr;
}
const KernelSet* kernel_set_neon() {
  return nullptr;
}

}  // namespace aprt::kernels
