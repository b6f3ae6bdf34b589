// Camera frame -> network input (centre crop, bilinear resize, colour
// conversion, normalisation in one pass; u8_f32_preprocess_impl.inl), one
// translation unit per ISA (kernels/simd/isa.h).
#include "kernels/table/simd_kernels.h"

namespace aprt::kernels {
namespace APRT_SIMD {
// clang-format off
#include APRT_SIMD_VEC
#include "kernels/preprocess/u8_f32_preprocess_impl.inl"
// clang-format on
}  // namespace APRT_SIMD

void APRT_SIMD_NAME(u8_f32_preprocess, )(const PreprocessPlan& plan, const ImageView& img,
                                         float* out) {
  APRT_SIMD::preprocess_rows(plan, img, out, 0, plan.params.size);
}

}  // namespace aprt::kernels
