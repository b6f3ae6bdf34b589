// bfloat16 (the upper 16 bits of an IEEE float: 8 exponent bits, 7 mantissa
// bits) as the bf16 attention uses it (issue #4; FORMAT.md "bf16 attention").
// The rounding is the one AVX-512 BF16's vcvtneps2bf16 performs, so the
// reference and the kernel round every value to the same bf16: to nearest,
// ties to even; a denormal input flushed to a zero of its sign (the
// instruction treats denormals as zero); a NaN stays a (quiet) NaN; values
// beyond the largest bf16 round to infinity.
#pragma once

#include <cstdint>
#include <cstring>

namespace aprt::kernels {

inline uint16_t bf16_bits(float x) {
  uint32_t u;
  std::memcpy(&u, &x, 4);
  if ((u & 0x7f800000u) == 0x7f800000u && (u & 0x007fffffu) != 0)
    return uint16_t((u >> 16) | 0x0040u);                            // NaN: quiet, sign kept
  if ((u & 0x7f800000u) == 0) return uint16_t((u >> 16) & 0x8000u);  // zero or denormal
  return uint16_t((u + 0x7fffu + ((u >> 16) & 1u)) >> 16);
}

inline float bf16_float(uint16_t b) {
  const uint32_t u = uint32_t(b) << 16;
  float x;
  std::memcpy(&x, &u, 4);
  return x;
}

// x rounded to the nearest bf16, as a float.
inline float bf16_round(float x) {
  return bf16_float(bf16_bits(x));
}

}  // namespace aprt::kernels
