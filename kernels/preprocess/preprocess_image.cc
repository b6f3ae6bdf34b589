#include "kernels/preprocess/preprocess_image.h"

namespace aprt::kernels {
namespace {

template <PixelFormat F>
inline void fetch(const ImageView& img, int x, int y, uint8_t* rgb) {
  const uint8_t* row = img.data + size_t(y) * img.stride;
  if constexpr (F == PixelFormat::kRgb24) {
    rgb[0] = row[3 * x];
    rgb[1] = row[3 * x + 1];
    rgb[2] = row[3 * x + 2];
  } else if constexpr (F == PixelFormat::kBgr24) {
    rgb[0] = row[3 * x + 2];
    rgb[1] = row[3 * x + 1];
    rgb[2] = row[3 * x];
  } else if constexpr (F == PixelFormat::kYuyv) {
    const uint8_t* m = row + (x / 2) * 4;
    yuv_to_rgb(m[(x & 1) ? 2 : 0], m[1], m[3], rgb);
  } else if constexpr (F == PixelFormat::kUyvy) {
    const uint8_t* m = row + (x / 2) * 4;
    yuv_to_rgb(m[(x & 1) ? 3 : 1], m[0], m[2], rgb);
  } else if constexpr (F == PixelFormat::kNv12) {
    const uint8_t* uv = img.data + size_t(img.height) * img.stride + size_t(y / 2) * img.stride;
    yuv_to_rgb(row[x], uv[(x / 2) * 2], uv[(x / 2) * 2 + 1], rgb);
  } else {
    rgb[0] = rgb[1] = rgb[2] = row[x];
  }
}

template <PixelFormat F>
void run(const PreprocessPlan& plan, const ImageView& img, float* out) {
  const PreprocessParams& p = plan.params;
  const int s = p.size, nc = p.channels;
  for (int oy = 0; oy < s; ++oy) {
    const int ya = plan.y0[oy], yb = plan.y1[oy];
    const float wy = plan.wy[oy];
    float* o = out + size_t(oy) * s * nc;
    for (int ox = 0; ox < s; ++ox, o += nc) {
      const int xa = plan.x0[ox], xb = plan.x1[ox];
      const float wx = plan.wx[ox];
      uint8_t a[3], b[3], c[3], d[3];
      fetch<F>(img, xa, ya, a);
      fetch<F>(img, xb, ya, b);
      fetch<F>(img, xa, yb, c);
      fetch<F>(img, xb, yb, d);
      for (int ch = 0; ch < nc; ++ch) {
        const float top = a[ch] / 255.0f * (1 - wx) + b[ch] / 255.0f * wx;
        const float bot = c[ch] / 255.0f * (1 - wx) + d[ch] / 255.0f * wx;
        const float v = top * (1 - wy) + bot * wy;
        o[ch] = (v - p.mean[ch]) / p.std[ch];
      }
    }
  }
}

}  // namespace

bool plan_preprocess(const PreprocessParams& p, PixelFormat format, int width, int height,
                     PreprocessPlan* plan,
                     void (*fast)(const PreprocessPlan&, const ImageView&, float*)) {
  if (p.size < 1 || p.size > PreprocessPlan::kMaxSize || width < 1 || height < 1) return false;
  if (p.channels != 1 && p.channels != 3) return false;
  for (int c = 0; c < p.channels; ++c) {
    if (!(p.std[c] > 0.0f)) return false;
  }
  if (fast) plan->fast = fast;
  plan->params = p;
  plan->width = width;
  plan->height = height;
  plan->format = format;
  const int side = width < height ? width : height;
  const int cx = (width - side) / 2, cy = (height - side) / 2;
  const double scale = double(side) / p.size;
  for (int o = 0; o < p.size; ++o) {
    double src = (o + 0.5) * scale - 0.5;
    if (src < 0) src = 0;
    const int i0 = int(src), i1 = i0 + 1 < side ? i0 + 1 : side - 1;
    const float w = float(src - i0);
    plan->x0[o] = cx + i0;
    plan->x1[o] = cx + i1;
    plan->wx[o] = w;
    plan->y0[o] = cy + i0;
    plan->y1[o] = cy + i1;
    plan->wy[o] = w;
  }
  return true;
}

void preprocess_image(const PreprocessPlan& plan, const ImageView& img, float* out) {
  if (plan.fast) return plan.fast(plan, img, out);
  preprocess_image_portable(plan, img, out);
}

void preprocess_image_portable(const PreprocessPlan& plan, const ImageView& img, float* out) {
  switch (plan.format) {
    case PixelFormat::kRgb24: return run<PixelFormat::kRgb24>(plan, img, out);
    case PixelFormat::kBgr24: return run<PixelFormat::kBgr24>(plan, img, out);
    case PixelFormat::kYuyv: return run<PixelFormat::kYuyv>(plan, img, out);
    case PixelFormat::kUyvy: return run<PixelFormat::kUyvy>(plan, img, out);
    case PixelFormat::kNv12: return run<PixelFormat::kNv12>(plan, img, out);
    case PixelFormat::kGray8: return run<PixelFormat::kGray8>(plan, img, out);
  }
}

}  // namespace aprt::kernels
