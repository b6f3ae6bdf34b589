// int8 GEMM, 6 rows x 16 columns per tile, AVX2 without VNNI: activations
// and weights widened to int16, vpmaddwd (two products per 32-bit lane,
// exact: |255 x 127 x 2| fits easily; vpmaddubsw would saturate), and the
// activation quantiser. Scheme and epilogue: kernels/gemm/qs8_gemm.h.
#include <immintrin.h>

#include <cstring>

#include "kernels/common/row_tiles.h"
#include "kernels/gemm/qs8_gemm.h"
#include "kernels/table/kernel_table.h"

namespace aprt::kernels {
namespace {

constexpr int kMr = 6, kNr = 16, kG = 2;

inline int32_t load_a(const uint8_t* p, int n) {  // two bytes as int16 pair, zero-padded
  return int32_t(p[0]) | (n > 1 ? int32_t(p[1]) << 16 : 0);
}

inline __m256i mask8(int cols) {
  return _mm256_cmpgt_epi32(_mm256_set1_epi32(cols), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
}

template <int R>
void tile(const QGemmArgs& g, int r0, int j0, int ncols, const int8_t* wp) {
  __m256i acc[R][2];
  for (int r = 0; r < R; ++r) acc[r][0] = acc[r][1] = _mm256_setzero_si256();
  const uint8_t* a[R];
  for (int r = 0; r < R; ++r) a[r] = g.a + size_t(r0 + r) * g.lda;
  const int groups = (g.k + kG - 1) / kG, full = g.k / kG;
  for (int gi = 0; gi < groups; ++gi) {
    const int8_t* w = wp + size_t(gi) * kNr * kG;
    const __m256i b0 = _mm256_cvtepi8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(w)));
    const __m256i b1 =
        _mm256_cvtepi8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(w + 16)));
    const int left = gi < full ? kG : g.k - gi * kG;  // a partial last group: one byte
#pragma GCC unroll 6
    for (int r = 0; r < R; ++r) {
      const __m256i av = _mm256_set1_epi32(load_a(a[r] + gi * kG, left));
      acc[r][0] = _mm256_add_epi32(acc[r][0], _mm256_madd_epi16(av, b0));
      acc[r][1] = _mm256_add_epi32(acc[r][1], _mm256_madd_epi16(av, b1));
    }
  }
  const __m256i za = _mm256_set1_epi32(g.a_zero);
  for (int h = 0; h < 2; ++h) {
    const int cols = ncols - 8 * h;
    if (cols <= 0) break;
    const __m256i m = mask8(cols);
    const int j = j0 + 8 * h;
    const __m256i cs = _mm256_maskload_epi32(g.w_colsum + j, m);
    const __m256 mult = _mm256_maskload_ps(g.mult + j, m);
    const __m256 bias = g.bias ? _mm256_maskload_ps(g.bias + j, m) : _mm256_setzero_ps();
    const __m256i corr = _mm256_mullo_epi32(za, cs);
    for (int r = 0; r < R; ++r) {
      const __m256i exact = _mm256_sub_epi32(acc[r][h], corr);
      __m256 y = _mm256_fmadd_ps(_mm256_cvtepi32_ps(exact), mult, bias);
      if (g.residual) {
        y = _mm256_add_ps(y, _mm256_maskload_ps(g.residual + size_t(r0 + r) * g.ldr + j, m));
      }
      if (g.act == Act::kRelu) y = _mm256_max_ps(y, _mm256_setzero_ps());
      _mm256_maskstore_ps(g.c + size_t(r0 + r) * g.ldc + j, m, y);
    }
  }
}

void gemm(const QGemmArgs& g, int r0, int r1, int p0, int p1) {
  const size_t panel = size_t((g.k + kG - 1) / kG) * kNr * kG;  // bytes per packed panel
  for_panel_tiles<kMr, kNr>(g.n, r0, r1, p0, p1, [&](auto rows, int r, int j0, int ncols, int p) {
    tile<rows()>(g, r, j0, ncols, g.w_packed + size_t(p) * panel);
  });
}

void quantize(size_t n, const float* x, float inv_scale, int32_t zero, uint8_t* q) {
  const __m256 s = _mm256_set1_ps(inv_scale), lo = _mm256_set1_ps(-512.0f),
               hi = _mm256_set1_ps(512.0f);
  const __m256i z = _mm256_set1_epi32(zero), qmax = _mm256_set1_epi32(255);
  size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    __m256 t = _mm256_min_ps(_mm256_max_ps(_mm256_mul_ps(_mm256_loadu_ps(x + i), s), lo), hi);
    __m256i v = _mm256_add_epi32(_mm256_cvtps_epi32(t), z);
    v = _mm256_min_epi32(_mm256_max_epi32(v, _mm256_setzero_si256()), qmax);
    const __m128i w16 = _mm_packus_epi32(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(q + i), _mm_packus_epi16(w16, w16));
  }
  if (i < n) {  // the tail through a small buffer
    float t[8] = {};
    uint8_t b[8];
    std::memcpy(t, x + i, (n - i) * sizeof(float));
    quantize(8, t, inv_scale, zero, b);
    std::memcpy(q + i, b, n - i);
  }
}

}  // namespace

extern const QKernelSet qs8_kernels__avx2;
const QKernelSet qs8_kernels__avx2 = {
    .isa = "avx2",
    .mr = kMr,
    .nr = kNr,
    .kgroup = kG,
    .gemm = gemm,
    .quantize = quantize,
    .dwconv_rows = qu8s8_dwconv2d__avx2,
};

}  // namespace aprt::kernels
