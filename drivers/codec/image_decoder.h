// PNG and JPEG files decoded to RGB24 into caller-provided memory.
//
// All memory is taken by create(): a buffer for the file's bytes, and an
// arena that libpng allocates from (reset for each image), so decoding a PNG
// allocates nothing. libjpeg-turbo's decompressor is created once and reused;
// its per-image internal buffers come from its own memory manager (malloc) --
// on the capture thread, never on the inference thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "runtime/base/expected.h"

namespace aprt {

struct DecodedImage {
  int width = 0, height = 0;
  size_t bytes = 0;  // width * height * 3
};

class ImageDecoder {
 public:
  // max_file_bytes: the largest file accepted; arena_bytes: libpng's working memory.
  static Expected<std::unique_ptr<ImageDecoder>> create(size_t max_file_bytes,
                                                        size_t arena_bytes = size_t(4) << 20);
  ~ImageDecoder();
  ImageDecoder(const ImageDecoder&) = delete;
  ImageDecoder& operator=(const ImageDecoder&) = delete;

  // Decodes `path` (PNG or JPEG, by content) to RGB24 rows in out[capacity].
  Expected<DecodedImage> decode(const char* path, uint8_t* out, size_t capacity);
  // Width and height only (reads the header).
  Expected<DecodedImage> probe(const char* path);
  // A JPEG already in memory (a camera's MJPEG frame) to RGB24 rows in
  // out[capacity]; `what` names it in errors. No file buffer is used.
  Expected<DecodedImage> decode_jpeg_memory(const uint8_t* data, size_t n, uint8_t* out,
                                            size_t capacity, const char* what);

  // Arena bump allocator used by libpng (public for the C callbacks).
  void* arena_alloc(size_t n);
  struct Jpeg;  // libjpeg state (public for the C error callback)

 private:
  ImageDecoder() = default;
  Expected<size_t> read_file(const char* path);
  Expected<DecodedImage> decode_png(const char* path, size_t n, uint8_t* out, size_t capacity,
                                    bool header_only);
  Expected<DecodedImage> decode_jpeg(const char* path, const uint8_t* data, size_t n, uint8_t* out,
                                     size_t capacity, bool header_only);

  uint8_t* file_ = nullptr;
  size_t file_capacity_ = 0;
  uint8_t* arena_ = nullptr;
  size_t arena_capacity_ = 0;
  size_t arena_used_ = 0;
  Jpeg* jpeg_ = nullptr;
};

}  // namespace aprt
