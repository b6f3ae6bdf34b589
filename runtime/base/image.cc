#include "runtime/base/image.h"

namespace aprt {

const char* pixel_format_name(PixelFormat f) {
  switch (f) {
    case PixelFormat::kRgb24: return "RGB24";
    case PixelFormat::kBgr24: return "BGR24";
    case PixelFormat::kYuyv: return "YUYV";
    case PixelFormat::kUyvy: return "UYVY";
    case PixelFormat::kNv12: return "NV12";
    case PixelFormat::kGray8: return "GRAY8";
  }
  return "?";
}

size_t min_stride(PixelFormat f, int width) {
  switch (f) {
    case PixelFormat::kRgb24:
    case PixelFormat::kBgr24: return size_t(width) * 3;
    case PixelFormat::kYuyv:
    case PixelFormat::kUyvy: return size_t((width + 1) / 2) * 4;
    case PixelFormat::kNv12:
    case PixelFormat::kGray8: return size_t(width);
  }
  return 0;
}

size_t frame_bytes(PixelFormat f, int width, int height) {
  if (f == PixelFormat::kNv12)
    return size_t(width) * height + size_t((width + 1) / 2) * 2 * ((height + 1) / 2);
  return min_stride(f, width) * size_t(height);
}

size_t image_span(PixelFormat f, int width, int height, size_t stride) {
  if (width <= 0 || height <= 0) return 0;
  if (f == PixelFormat::kNv12) {
    const size_t uv_rows = size_t(height + 1) / 2;
    return stride * (size_t(height) + uv_rows - 1) + size_t((width + 1) / 2) * 2;
  }
  return stride * size_t(height - 1) + min_stride(f, width);
}

}  // namespace aprt
