#include "kernels/preprocess/u8_f32_preprocess__ref.h"

#include <cmath>

namespace aprt::kernels {

void pixel_rgb(const ImageView& img, int x, int y, uint8_t* rgb) {
  const uint8_t* row = img.data + size_t(y) * img.stride;
  switch (img.format) {
    case PixelFormat::kRgb24:
      rgb[0] = row[3 * x];
      rgb[1] = row[3 * x + 1];
      rgb[2] = row[3 * x + 2];
      return;
    case PixelFormat::kBgr24:
      rgb[0] = row[3 * x + 2];
      rgb[1] = row[3 * x + 1];
      rgb[2] = row[3 * x];
      return;
    case PixelFormat::kYuyv: {
      const uint8_t* m = row + (x / 2) * 4;
      yuv_to_rgb(m[(x & 1) ? 2 : 0], m[1], m[3], rgb);
      return;
    }
    case PixelFormat::kUyvy: {
      const uint8_t* m = row + (x / 2) * 4;
      yuv_to_rgb(m[(x & 1) ? 3 : 1], m[0], m[2], rgb);
      return;
    }
    case PixelFormat::kNv12: {
      const uint8_t* uv = img.data + size_t(img.height) * img.stride + size_t(y / 2) * img.stride;
      yuv_to_rgb(row[x], uv[(x / 2) * 2], uv[(x / 2) * 2 + 1], rgb);
      return;
    }
    case PixelFormat::kGray8: rgb[0] = rgb[1] = rgb[2] = row[x]; return;
  }
}

void u8_f32_preprocess__ref(const ImageView& img, const PreprocessParams& p, float* out) {
  const int side = img.width < img.height ? img.width : img.height;
  const int x0 = (img.width - side) / 2, y0 = (img.height - side) / 2;
  const double scale = double(side) / p.size;
  for (int oy = 0; oy < p.size; ++oy) {
    double sy = (oy + 0.5) * scale - 0.5;
    if (sy < 0) sy = 0;
    const int iy0 = int(sy), iy1 = iy0 + 1 < side ? iy0 + 1 : side - 1;
    const float wy = float(sy - iy0);
    for (int ox = 0; ox < p.size; ++ox) {
      double sx = (ox + 0.5) * scale - 0.5;
      if (sx < 0) sx = 0;
      const int ix0 = int(sx), ix1 = ix0 + 1 < side ? ix0 + 1 : side - 1;
      const float wx = float(sx - ix0);
      uint8_t a[3], b[3], c[3], d[3];
      pixel_rgb(img, x0 + ix0, y0 + iy0, a);
      pixel_rgb(img, x0 + ix1, y0 + iy0, b);
      pixel_rgb(img, x0 + ix0, y0 + iy1, c);
      pixel_rgb(img, x0 + ix1, y0 + iy1, d);
      float* o = out + (size_t(oy) * p.size + ox) * p.channels;
      for (int ch = 0; ch < p.channels; ++ch) {
        // Channel 0 of a 1-channel model is the gray value (R == G == B for gray input).
        const float top = a[ch] / 255.0f * (1 - wx) + b[ch] / 255.0f * wx;
        const float bot = c[ch] / 255.0f * (1 - wx) + d[ch] / 255.0f * wx;
        const float v = top * (1 - wy) + bot * wy;
        o[ch] = (v - p.mean[ch]) / p.std[ch];
      }
    }
  }
}

}  // namespace aprt::kernels
