#pragma once

#include "kernels/preprocess/preprocess_image.h"

namespace aprt::kernels {

// 8-bit RGB (or gray) of pixel (x, y) of any supported format.
void pixel_rgb(const ImageView& img, int x, int y, uint8_t* rgb);

// The training transform, written for clarity: every output value recomputes
// its source coordinates and converts its four neighbours. The oracle of the
// table-driven kernel below and of the tests against the Python transform.
void u8_f32_preprocess__ref(const ImageView& img, const PreprocessParams& p, float* out);

}  // namespace aprt::kernels
