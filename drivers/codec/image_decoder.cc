#include "drivers/codec/image_decoder.h"

#if APRT_HAVE_IMAGE_CODECS
#include <fcntl.h>
#include <png.h>
#include <setjmp.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <new>

// jpeglib.h needs FILE and size_t declared first.
#include <jpeglib.h>

#include "runtime/base/check.h"
#include "runtime/base/file_io.h"

namespace aprt {

struct ImageDecoder::Jpeg {
  jpeg_decompress_struct cinfo;
  jpeg_error_mgr err;
  jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
  int warnings;  // corrupt-data warnings of the current image
};

namespace {

void jpeg_error_exit(j_common_ptr cinfo) {
  auto* j = reinterpret_cast<ImageDecoder::Jpeg*>(cinfo->client_data);
  (*cinfo->err->format_message)(cinfo, j->message);
  longjmp(j->jump, 1);
}

// libjpeg reports corrupt or truncated data as warnings (and fills the rest
// of the image with grey); count them so the image is refused, not used.
void jpeg_warning(j_common_ptr cinfo, int level) {
  if (level >= 0) return;  // trace messages
  auto* j = reinterpret_cast<ImageDecoder::Jpeg*>(cinfo->client_data);
  if (j->warnings++ == 0) (*cinfo->err->format_message)(cinfo, j->message);
}

struct PngSource {
  const uint8_t* data;
  size_t size, pos;
};

void png_read_mem(png_structp png, png_bytep out, png_size_t n) {
  auto* src = static_cast<PngSource*>(png_get_io_ptr(png));
  if (src->pos + n > src->size) {
    png_error(png, "file is truncated");
    return;
  }
  std::memcpy(out, src->data + src->pos, n);
  src->pos += n;
}

png_voidp png_arena_malloc(png_structp png, png_alloc_size_t n) {
  return static_cast<ImageDecoder*>(png_get_mem_ptr(png))->arena_alloc(n);
}
void png_arena_free(png_structp, png_voidp) {}  // the arena is reset per image

struct PngErrorState {
  char message[128];
};
void png_error_fn(png_structp png, png_const_charp msg) {
  auto* st = static_cast<PngErrorState*>(png_get_error_ptr(png));
  std::snprintf(st->message, sizeof st->message, "%s", msg);
  png_longjmp(png, 1);
}
void png_warning_fn(png_structp, png_const_charp) {}

}  // namespace

Expected<std::unique_ptr<ImageDecoder>> ImageDecoder::create(size_t max_file_bytes,
                                                             size_t arena_bytes) {
  std::unique_ptr<ImageDecoder> d(new (std::nothrow) ImageDecoder());
  APRT_ENSURE(d != nullptr, Errc::kOutOfMemory, "image decoder: out of memory");
  void* f =
      mmap(nullptr, max_file_bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  void* a = mmap(nullptr, arena_bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  APRT_ENSURE(f != MAP_FAILED && a != MAP_FAILED, Errc::kOutOfMemory,
              "image decoder: cannot map its buffers: %s", std::strerror(errno));
  d->file_ = static_cast<uint8_t*>(f);
  d->file_capacity_ = max_file_bytes;
  d->arena_ = static_cast<uint8_t*>(a);
  d->arena_capacity_ = arena_bytes;
  d->jpeg_ = new (std::nothrow) Jpeg();
  APRT_ENSURE(d->jpeg_ != nullptr, Errc::kOutOfMemory, "image decoder: out of memory");
  d->jpeg_->cinfo.err = jpeg_std_error(&d->jpeg_->err);
  d->jpeg_->err.error_exit = jpeg_error_exit;
  d->jpeg_->err.emit_message = jpeg_warning;
  d->jpeg_->cinfo.client_data = d->jpeg_;
  jpeg_create_decompress(&d->jpeg_->cinfo);
  return d;
}

ImageDecoder::~ImageDecoder() {
  if (jpeg_) {
    jpeg_destroy_decompress(&jpeg_->cinfo);
    delete jpeg_;
  }
  if (file_) munmap(file_, file_capacity_);
  if (arena_) munmap(arena_, arena_capacity_);
}

void* ImageDecoder::arena_alloc(size_t n) {
  const size_t need = (n + 15) & ~size_t(15);
  if (arena_used_ + need > arena_capacity_) return nullptr;  // libpng reports out of memory
  void* p = arena_ + arena_used_;
  arena_used_ += need;
  return p;
}

// A regular file of at most file_capacity_ bytes (a FIFO or a device at the
// path is refused, never read: runtime/base/file_io.h).
Expected<size_t> ImageDecoder::read_file(const char* path) {
  auto f = open_input_file(path, file_capacity_, "image");
  if (!f) return f.error();
  const long got = f->read(file_, size_t(f->size()));
  APRT_ENSURE(got >= 0, Errc::kIo, "image: reading '%s': %s", path, std::strerror(errno));
  return size_t(got);
}

Expected<DecodedImage> ImageDecoder::decode(const char* path, uint8_t* out, size_t capacity) {
  auto n = read_file(path);
  if (!n) return n.error();
  static const uint8_t kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (*n >= 8 && std::memcmp(file_, kPng, 8) == 0)
    return decode_png(path, *n, out, capacity, false);
  if (*n >= 3 && file_[0] == 0xFF && file_[1] == 0xD8 && file_[2] == 0xFF) {
    return decode_jpeg(path, file_, *n, out, capacity, false);
  }
  return Error(Errc::kUnsupported, "image: '%s' is neither PNG nor JPEG", path);
}

Expected<DecodedImage> ImageDecoder::probe(const char* path) {
  auto n = read_file(path);
  if (!n) return n.error();
  static const uint8_t kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (*n >= 8 && std::memcmp(file_, kPng, 8) == 0) return decode_png(path, *n, nullptr, 0, true);
  if (*n >= 3 && file_[0] == 0xFF && file_[1] == 0xD8)
    return decode_jpeg(path, file_, *n, nullptr, 0, true);
  return Error(Errc::kUnsupported, "image: '%s' is neither PNG nor JPEG", path);
}

Expected<DecodedImage> ImageDecoder::decode_png(const char* path, size_t n, uint8_t* out,
                                                size_t capacity, bool header_only) {
  arena_used_ = 0;
  PngErrorState err{};
  png_structp png =
      png_create_read_struct_2(PNG_LIBPNG_VER_STRING, &err, png_error_fn, png_warning_fn, this,
                               png_arena_malloc, png_arena_free);
  APRT_ENSURE(png != nullptr, Errc::kOutOfMemory, "image: '%s': libpng could not start", path);
  png_infop info = png_create_info_struct(png);
  PngSource src{file_, n, 0};
  DecodedImage img;
  // Everything libpng needs lives in the arena: no cleanup on the error path.
  if (setjmp(png_jmpbuf(png))) {
    return Error(Errc::kBadHeader, "image: '%s': PNG decode failed: %s", path, err.message);
  }
  png_set_read_fn(png, &src, png_read_mem);
  png_read_info(png, info);
  const png_uint_32 w = png_get_image_width(png, info), h = png_get_image_height(png, info);
  if (w == 0 || h == 0 || w > 16384 || h > 16384) {
    return Error(Errc::kTooLarge, "image: '%s': %ux%u pixels is out of range", path, w, h);
  }
  img.width = int(w);
  img.height = int(h);
  img.bytes = size_t(w) * h * 3;
  if (header_only) return img;
  if (img.bytes > capacity) {
    return Error(Errc::kTooLarge, "image: '%s' (%dx%d) does not fit the %zu-byte frame buffer",
                 path, img.width, img.height, capacity);
  }
  const int type = png_get_color_type(png, info), depth = png_get_bit_depth(png, info);
  if (type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (type == PNG_COLOR_TYPE_GRAY || type == PNG_COLOR_TYPE_GRAY_ALPHA) png_set_gray_to_rgb(png);
  if (type == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (depth == 16) png_set_strip_16(png);
  if (type & PNG_COLOR_MASK_ALPHA) png_set_strip_alpha(png);
  if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_strip_alpha(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  if (png_get_rowbytes(png, info) != size_t(w) * 3) {
    return Error(Errc::kUnsupported, "image: '%s': unsupported PNG layout", path);
  }
  const int passes = png_set_interlace_handling(png);
  for (int pass = 0; pass < passes; ++pass) {
    for (png_uint_32 y = 0; y < h; ++y) png_read_row(png, out + size_t(y) * w * 3, nullptr);
  }
  png_read_end(png, nullptr);
  return img;
}

Expected<DecodedImage> ImageDecoder::decode_jpeg_memory(const uint8_t* data, size_t n, uint8_t* out,
                                                        size_t capacity, const char* what) {
  if (n < 4 || data[0] != 0xFF || data[1] != 0xD8) {
    return Error(Errc::kBadHeader, "image: %s: not a JPEG (no SOI marker; %zu bytes)", what, n);
  }
  return decode_jpeg(what, data, n, out, capacity, false);
}

Expected<DecodedImage> ImageDecoder::decode_jpeg(const char* path, const uint8_t* data, size_t n,
                                                 uint8_t* out, size_t capacity, bool header_only) {
  jpeg_decompress_struct& c = jpeg_->cinfo;
  DecodedImage img;
  if (setjmp(jpeg_->jump)) {
    jpeg_abort_decompress(&c);
    return Error(Errc::kBadHeader, "image: '%s': JPEG decode failed: %s", path, jpeg_->message);
  }
  jpeg_->warnings = 0;
  jpeg_mem_src(&c, data, static_cast<unsigned long>(n));
  jpeg_read_header(&c, TRUE);
  c.out_color_space = JCS_RGB;
  img.width = int(c.image_width);
  img.height = int(c.image_height);
  img.bytes = size_t(img.width) * img.height * 3;
  if (header_only || img.bytes > capacity) {
    jpeg_abort_decompress(&c);
    if (header_only) return img;
    return Error(Errc::kTooLarge, "image: '%s' (%dx%d) does not fit the %zu-byte frame buffer",
                 path, img.width, img.height, capacity);
  }
  jpeg_start_decompress(&c);
  while (c.output_scanline < c.output_height) {
    JSAMPROW row = out + size_t(c.output_scanline) * img.width * 3;
    jpeg_read_scanlines(&c, &row, 1);
  }
  jpeg_finish_decompress(&c);
  if (jpeg_->warnings) {
    return Error(Errc::kTruncated, "image: '%s': corrupt or truncated JPEG data (%s)", path,
                 jpeg_->message);
  }
  return img;
}

}  // namespace aprt

#else  // built without libpng / libjpeg for this target

#include "runtime/base/check.h"

namespace aprt {

struct ImageDecoder::Jpeg {};

Expected<std::unique_ptr<ImageDecoder>> ImageDecoder::create(size_t, size_t) {
  return Error(Errc::kUnsupported,
               "image decoder: this build has no PNG/JPEG support (libpng/libjpeg were not found "
               "for the target when it was configured)");
}
ImageDecoder::~ImageDecoder() = default;
void* ImageDecoder::arena_alloc(size_t) {
  return nullptr;
}
Expected<DecodedImage> ImageDecoder::decode(const char* path, uint8_t*, size_t) {
  return Error(Errc::kUnsupported, "image decoder: cannot decode '%s': this build has no PNG/JPEG",
               path);
}
Expected<DecodedImage> ImageDecoder::probe(const char* path) {
  return Error(Errc::kUnsupported, "image decoder: cannot read '%s': this build has no PNG/JPEG",
               path);
}
Expected<DecodedImage> ImageDecoder::decode_jpeg_memory(const uint8_t*, size_t, uint8_t*, size_t,
                                                        const char* what) {
  return Error(Errc::kUnsupported, "image decoder: cannot decode %s: this build has no JPEG", what);
}

}  // namespace aprt
#endif
