// Camera frame -> network input (centre crop, bilinear resize, colour
// conversion, normalisation in one pass), avx512. See simd/preprocess_impl.inl.
#include <immintrin.h>

#include <cstdint>

#include "kernels/common/preprocess_image.h"

namespace aprt::kernels {
namespace avx512 {
// clang-format off
#include "kernels/simd/vec_avx512.h"
#include "kernels/simd/preprocess_impl.inl"
// clang-format on
}  // namespace avx512

void u8_f32_preprocess__avx512(const PreprocessPlan& plan, const ImageView& img, float* out) {
  avx512::preprocess_rows(plan, img, out, 0, plan.params.size);
}

}  // namespace aprt::kernels
