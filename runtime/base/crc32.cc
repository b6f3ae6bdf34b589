#include "runtime/base/crc32.h"

#include <array>
#include <cstring>

#if defined(__x86_64__)
#include <immintrin.h>
#elif defined(__aarch64__)
#include <arm_acle.h>
#include <asm/hwcap.h>
#include <sys/auxv.h>
#endif

namespace aprt {
namespace {

// Slice-by-8 tables: 8 KiB, built at compile time.
constexpr std::array<std::array<uint32_t, 256>, 8> make_tables() {
  std::array<std::array<uint32_t, 256>, 8> t{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[0][i] = c;
  }
  for (uint32_t i = 0; i < 256; ++i) {
    for (int s = 1; s < 8; ++s) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xFF];
  }
  return t;
}

constexpr auto kTables = make_tables();

// The register update (no inversions) over bytes, by table.
uint32_t update_table(uint32_t c, const unsigned char* p, size_t size) noexcept {
  while (size >= 8) {
    uint32_t lo, hi;
    std::memcpy(&lo, p, 4);
    std::memcpy(&hi, p + 4, 4);
    lo ^= c;  // little-endian hosts only (checked in model_file.cc)
    c = kTables[7][lo & 0xFF] ^ kTables[6][(lo >> 8) & 0xFF] ^ kTables[5][(lo >> 16) & 0xFF] ^
        kTables[4][lo >> 24] ^ kTables[3][hi & 0xFF] ^ kTables[2][(hi >> 8) & 0xFF] ^
        kTables[1][(hi >> 16) & 0xFF] ^ kTables[0][hi >> 24];
    p += 8;
    size -= 8;
  }
  while (size--) c = kTables[0][(c ^ *p++) & 0xFF] ^ (c >> 8);
  return c;
}

#if defined(__x86_64__)

// Folding by carry-less multiplication: four 128-bit lanes advance 64 bytes
// per step (x^(512±64) mod P), fold into one (x^(128±64) mod P), then 128 ->
// 64 -> 32 bits and a Barrett reduction. The constants are those powers of x
// modulo P = 0x104C11DB7, bit-reflected (the paper's k1..k5, mu, P').
// Takes n >= 64, a multiple of 16.
#define APRT_CRC_TARGET __attribute__((target("pclmul,sse4.1")))

APRT_CRC_TARGET inline __m128i load16(const unsigned char* q) {
  return _mm_loadu_si128(reinterpret_cast<const __m128i*>(q));
}

// x advanced by the distance k encodes, plus the next 16 bytes.
APRT_CRC_TARGET inline __m128i fold(__m128i x, __m128i k, __m128i next) {
  return _mm_xor_si128(
      _mm_xor_si128(_mm_clmulepi64_si128(x, k, 0x00), _mm_clmulepi64_si128(x, k, 0x11)), next);
}

APRT_CRC_TARGET uint32_t update_pclmul(uint32_t c, const unsigned char* p, size_t n) noexcept {
  const __m128i k1k2 = _mm_set_epi64x(0x1c6e41596, 0x154442bd4);
  const __m128i k3k4 = _mm_set_epi64x(0x0ccaa009e, 0x1751997d0);
  const __m128i k5 = _mm_set_epi64x(0, 0x163cd6124);
  const __m128i poly_mu = _mm_set_epi64x(0x1f7011641, 0x1db710641);
  const __m128i mask32 = _mm_set_epi32(0, 0, 0, -1);
  __m128i x0 = _mm_xor_si128(load16(p), _mm_cvtsi32_si128(int(c)));
  __m128i x1 = load16(p + 16), x2 = load16(p + 32), x3 = load16(p + 48);
  p += 64;
  n -= 64;
  for (; n >= 64; p += 64, n -= 64) {
    x0 = fold(x0, k1k2, load16(p));
    x1 = fold(x1, k1k2, load16(p + 16));
    x2 = fold(x2, k1k2, load16(p + 32));
    x3 = fold(x3, k1k2, load16(p + 48));
  }
  x0 = fold(x0, k3k4, x1);
  x0 = fold(x0, k3k4, x2);
  x0 = fold(x0, k3k4, x3);
  for (; n >= 16; p += 16, n -= 16) x0 = fold(x0, k3k4, load16(p));
  // 128 -> 64 bits (appending 32 zero bits), then 64 -> 32.
  x0 = _mm_xor_si128(_mm_clmulepi64_si128(x0, k3k4, 0x10), _mm_srli_si128(x0, 8));
  x0 = _mm_xor_si128(_mm_clmulepi64_si128(_mm_and_si128(x0, mask32), k5, 0x00),
                     _mm_srli_si128(x0, 4));
  // Barrett: q = (low 32 bits * mu) mod x^32, then subtract q * P.
  __m128i t = _mm_clmulepi64_si128(_mm_and_si128(x0, mask32), poly_mu, 0x10);
  t = _mm_clmulepi64_si128(_mm_and_si128(t, mask32), poly_mu, 0x00);
  return uint32_t(_mm_extract_epi32(_mm_xor_si128(x0, t), 1));
}

bool has_fast() noexcept {
  static const bool yes = __builtin_cpu_supports("pclmul") && __builtin_cpu_supports("sse4.1");
  return yes;
}

uint32_t update_fast(uint32_t c, const unsigned char* p, size_t size) noexcept {
  if (size >= 64) {
    const size_t body = size & ~size_t(15);
    c = update_pclmul(c, p, body);
    p += body;
    size -= body;
  }
  return update_table(c, p, size);
}

constexpr const char* kFastName = "pclmul";

#elif defined(__aarch64__)

__attribute__((target("+crc"))) uint32_t update_fast(uint32_t c, const unsigned char* p,
                                                     size_t size) noexcept {
  for (; size >= 8; p += 8, size -= 8) {
    uint64_t v;
    std::memcpy(&v, p, 8);
    c = __crc32d(c, v);
  }
  for (; size; ++p, --size) c = __crc32b(c, *p);
  return c;
}

bool has_fast() noexcept {
  static const bool yes = (getauxval(AT_HWCAP) & HWCAP_CRC32) != 0;
  return yes;
}

constexpr const char* kFastName = "armv8-crc";

#else

bool has_fast() noexcept {
  return false;
}
uint32_t update_fast(uint32_t c, const unsigned char* p, size_t size) noexcept {
  return update_table(c, p, size);
}
constexpr const char* kFastName = "table";

#endif

}  // namespace

uint32_t crc32__table(const void* data, size_t size, uint32_t crc) noexcept {
  return ~update_table(~crc, static_cast<const unsigned char*>(data), size);
}

uint32_t crc32(const void* data, size_t size, uint32_t crc) noexcept {
  const auto* p = static_cast<const unsigned char*>(data);
  return ~(has_fast() ? update_fast(~crc, p, size) : update_table(~crc, p, size));
}

const char* crc32_implementation() noexcept {
  return has_fast() ? kFastName : "table";
}

}  // namespace aprt
