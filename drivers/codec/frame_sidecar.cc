#include "drivers/codec/frame_sidecar.h"

#include <cstdio>
#include <cstring>

#include "runtime/base/check.h"
#include "runtime/base/text_lines.h"

namespace aprt {
namespace {

constexpr const char* kWhat = "frame sidecar";

bool parse_format(const char* s, PixelFormat* f) {
  for (PixelFormat p : {PixelFormat::kRgb24, PixelFormat::kBgr24, PixelFormat::kYuyv,
                        PixelFormat::kUyvy, PixelFormat::kNv12, PixelFormat::kGray8}) {
    if (std::strcmp(s, pixel_format_name(p)) == 0) {
      *f = p;
      return true;
    }
  }
  return false;
}

}  // namespace

Expected<FrameSidecar> parse_frame_sidecar(std::string_view text, const char* path) {
  FrameSidecar s;
  enum : unsigned { kFormat = 1, kWidth = 2, kHeight = 4, kStride = 8, kBytes = 16, kPose = 32 };
  unsigned seen = 0;
  Status st = each_text_line(text, kWhat, path, true, [&](char* line, int lineno) -> Status {
    char* f[9];
    const int n = split_fields(line, f, 8);
    const char* key = f[0];
    auto once = [&](unsigned bit) -> Status {
      APRT_ENSURE(!(seen & bit), Errc::kBadMetadata, "%s: %s:%d: '%s' given twice", kWhat, path,
                  lineno, key);
      seen |= bit;
      return ok();
    };
    auto integer = [&](unsigned bit, int64_t lo, int64_t hi, int64_t* v) -> Status {
      if (Status o = once(bit); !o) return o;
      APRT_ENSURE(n == 2 && parse_integer(f[1], lo, hi, v), Errc::kBadMetadata,
                  "%s: %s:%d: '%s' needs one integer in [%lld, %lld]", kWhat, path, lineno, key,
                  static_cast<long long>(lo), static_cast<long long>(hi));
      return ok();
    };
    int64_t v = 0;
    if (std::strcmp(key, "format") == 0) {
      if (Status o = once(kFormat); !o) return o;
      APRT_ENSURE(n == 2 && parse_format(f[1], &s.format), Errc::kBadMetadata,
                  "%s: %s:%d: unknown pixel format '%s'", kWhat, path, lineno, n >= 2 ? f[1] : "");
    } else if (std::strcmp(key, "width") == 0) {
      if (Status o = integer(kWidth, 1, kMaxSidecarSide, &v); !o) return o;
      s.width = int(v);
    } else if (std::strcmp(key, "height") == 0) {
      if (Status o = integer(kHeight, 1, kMaxSidecarSide, &v); !o) return o;
      s.height = int(v);
    } else if (std::strcmp(key, "stride") == 0) {
      if (Status o = integer(kStride, 1, int64_t(16) * 3 * kMaxSidecarSide, &v); !o) return o;
      s.stride = size_t(v);
    } else if (std::strcmp(key, "bytes") == 0) {
      if (Status o = integer(kBytes, 1, int64_t(kMaxSidecarFrameBytes), &v); !o) return o;
      s.bytes = size_t(v);
    } else if (std::strcmp(key, "pose") == 0) {
      if (Status o = once(kPose); !o) return o;
      APRT_ENSURE(n == 8, Errc::kBadMetadata, "%s: %s:%d: 'pose' needs 7 numbers", kWhat, path,
                  lineno);
      for (int k = 0; k < 7; ++k) {
        APRT_ENSURE(parse_finite(f[1 + k], &s.pose[k]), Errc::kBadMetadata,
                    "%s: %s:%d: '%s' is not a finite number", kWhat, path, lineno, f[1 + k]);
      }
      s.have_pose = true;
    } else {
      // name, model, isa, flags and keys of later versions: informative.
    }
    return ok();
  });
  if (!st) return st.error();
  const unsigned need = kFormat | kWidth | kHeight | kStride | kBytes;
  APRT_ENSURE((seen & need) == need, Errc::kBadMetadata,
              "%s: %s lacks one of format, width, height, stride, bytes", kWhat, path);
  const size_t row = min_stride(s.format, s.width);
  APRT_ENSURE(s.stride >= row && s.stride <= 16 * row, Errc::kBadMetadata,
              "%s: %s: stride %zu for %d %s pixels a row (at least %zu, at most 16 times that)",
              kWhat, path, s.stride, s.width, pixel_format_name(s.format), row);
  const size_t span = image_span(s.format, s.width, s.height, s.stride);
  APRT_ENSURE(s.bytes >= span, Errc::kBadMetadata,
              "%s: %s: %zu bytes cannot hold %dx%d %s rows %zu bytes apart (%zu needed)", kWhat,
              path, s.bytes, s.width, s.height, pixel_format_name(s.format), s.stride, span);
  return s;
}

std::string format_frame_sidecar(const FrameSidecar& s, const char* name, const char* model,
                                 const char* isa, uint32_t flags) {
  char geometry[160], pose[240];
  std::snprintf(geometry, sizeof geometry,
                "format %s\nwidth %d\nheight %d\nstride %zu\nbytes %zu\n",
                pixel_format_name(s.format), s.width, s.height, s.stride, s.bytes);
  std::snprintf(pose, sizeof pose, "pose %.9g %.9g %.9g %.9g %.9g %.9g %.9g\nflags %u\n", s.pose[0],
                s.pose[1], s.pose[2], s.pose[3], s.pose[4], s.pose[5], s.pose[6], flags);
  // name, model and isa are informative (the parser reads past them).
  return std::string(geometry) + "name " + name + "\nmodel " + model + "\nisa " + isa + "\n" + pose;
}

}  // namespace aprt
