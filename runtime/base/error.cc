#include "runtime/base/error.h"

#include <cstdio>
#include <cstring>
#include <initializer_list>

namespace aprt {

const char* errc_name(Errc code) noexcept {
  switch (code) {
    case Errc::kOk: return "ok";
    case Errc::kIo: return "io";
    case Errc::kTruncated: return "truncated";
    case Errc::kBadMagic: return "bad_magic";
    case Errc::kUnsupportedVersion: return "unsupported_version";
    case Errc::kBadHeader: return "bad_header";
    case Errc::kChecksum: return "checksum";
    case Errc::kSectionBounds: return "section_bounds";
    case Errc::kMisaligned: return "misaligned";
    case Errc::kBadMetadata: return "bad_metadata";
    case Errc::kBadTensor: return "bad_tensor";
    case Errc::kBadOp: return "bad_op";
    case Errc::kShapeMismatch: return "shape_mismatch";
    case Errc::kBadGraph: return "bad_graph";
    case Errc::kTooLarge: return "too_large";
    case Errc::kOutOfMemory: return "out_of_memory";
    case Errc::kWrongTarget: return "wrong_target";
    case Errc::kInvalidArgument: return "invalid_argument";
    case Errc::kUnsupported: return "unsupported";
    case Errc::kNotReady: return "not_ready";
    case Errc::kNotFound: return "not_found";
    case Errc::kIsaUnavailable: return "isa_unavailable";
  }
  return "unknown";
}

Error::Error(Errc code, const char* format, ...) noexcept : code_(code) {
  va_list args;
  va_start(args, format);
  std::vsnprintf(message_, kCapacity, format, args);
  va_end(args);
}

Error& Error::with_context(const char* format, ...) noexcept {
  char prefix[kCapacity];
  va_list args;
  va_start(args, format);
  int n = std::vsnprintf(prefix, kCapacity, format, args);
  va_end(args);
  if (n < 0) return *this;
  // Truncation at capacity is intended: build "prefix: message" by hand.
  char joined[kCapacity];
  size_t used = 0;
  for (const char* part :
       {static_cast<const char*>(prefix), ": ", static_cast<const char*>(message_)}) {
    const size_t len = std::strlen(part);
    const size_t room = kCapacity - 1 - used;
    const size_t take = len < room ? len : room;
    std::memcpy(joined + used, part, take);
    used += take;
  }
  joined[used] = '\0';
  std::memcpy(message_, joined, used + 1);
  return *this;
}

}  // namespace aprt
