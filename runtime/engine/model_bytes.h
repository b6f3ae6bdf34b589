// Reading the model file's little-endian fields (model_bin/FORMAT.md) from
// bytes of any alignment; model_file.cc and model_meta.cc only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "runtime/base/expected.h"
#include "runtime/engine/model_file.h"

namespace aprt {

template <class T>
T load(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

// Reserved bytes and flags must be 0 (FORMAT.md).
inline bool all_zero(const uint8_t* p, size_t n) {
  for (size_t i = 0; i < n; ++i) {
    if (p[i] != 0) return false;
  }
  return true;
}

// n bytes of a string field into dst (cap bytes, always NUL-terminated).
inline void copy_str(char* dst, size_t cap, const uint8_t* src, size_t n) {
  const size_t k = n < cap - 1 ? n : cap - 1;
  std::memcpy(dst, src, k);
  dst[k] = '\0';
}

// The META section (its bytes) into *out, every key checked: types, counts,
// finite values, the keys the modality requires.
Status parse_model_meta(const uint8_t* data, uint64_t size, ModelMeta* out);

}  // namespace aprt
