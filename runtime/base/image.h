// Camera frames as every layer sees them: pixel formats and a view of one
// frame's bytes (drivers produce them, the preprocessing kernels read them).
#pragma once

#include <cstddef>
#include <cstdint>

namespace aprt {

enum class PixelFormat : uint8_t {
  kRgb24,  // R G B bytes
  kBgr24,  // B G R bytes
  kYuyv,   // Y0 U Y1 V (4:2:2), BT.601 limited range
  kUyvy,   // U Y0 V Y1
  kNv12,   // Y plane, then interleaved U V plane at half resolution (4:2:0)
  kGray8,
};

const char* pixel_format_name(PixelFormat f);
// Bytes per row a tightly packed frame of this width needs (the Y plane for NV12).
size_t min_stride(PixelFormat f, int width);
// Bytes of a tightly packed frame.
size_t frame_bytes(PixelFormat f, int width, int height);
// Bytes from a frame's first to one past its last byte read, rows `stride`
// apart (the NV12 UV plane `height` rows after the Y plane, same stride): a
// buffer of fewer bytes, or a stride below min_stride(), is not this frame.
size_t image_span(PixelFormat f, int width, int height, size_t stride);

struct ImageView {
  const uint8_t* data;
  PixelFormat format;
  int width, height;
  size_t stride;  // bytes per row (of the Y plane for NV12; the UV plane follows height rows later)
};

// YUV (BT.601, limited range) -> 8-bit RGB, rounded: the one formula both the
// kernels and the Python reference use.
inline void yuv_to_rgb(int y, int u, int v, uint8_t* rgb) {
  const int c = y - 16, d = u - 128, e = v - 128;
  auto clamp = [](int x) { return uint8_t(x < 0 ? 0 : (x > 255 ? 255 : x)); };
  rgb[0] = clamp((298 * c + 409 * e + 128) >> 8);
  rgb[1] = clamp((298 * c - 100 * d - 208 * e + 128) >> 8);
  rgb[2] = clamp((298 * c + 516 * d + 128) >> 8);
}

}  // namespace aprt
