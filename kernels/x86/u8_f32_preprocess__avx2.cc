// Camera frame -> network input (centre crop, bilinear resize, colour
// conversion, normalisation in one pass), avx2. See simd/preprocess_impl.inl.
#include <immintrin.h>

#include <cstdint>

#include "kernels/common/preprocess_image.h"

namespace aprt::kernels {
namespace avx2 {
// clang-format off
#include "kernels/simd/vec_avx2.h"
#include "kernels/simd/preprocess_impl.inl"
// clang-format on
}  // namespace avx2

void u8_f32_preprocess__avx2(const PreprocessPlan& plan, const ImageView& img, float* out) {
  avx2::preprocess_rows(plan, img, out, 0, plan.params.size);
}

}  // namespace aprt::kernels
