// Camera frame -> network input (centre crop, bilinear resize, colour
// conversion, normalisation in one pass), neon. See simd/preprocess_impl.inl.
#include <arm_neon.h>

#include <cstdint>

#include "kernels/common/preprocess_image.h"

namespace aprt::kernels {
namespace neon {
// clang-format off
#include "kernels/simd/vec_neon.h"
#include "kernels/simd/preprocess_impl.inl"
// clang-format on
}  // namespace neon

void u8_f32_preprocess__neon(const PreprocessPlan& plan, const ImageView& img, float* out) {
  neon::preprocess_rows(plan, img, out, 0, plan.params.size);
}

}  // namespace aprt::kernels
