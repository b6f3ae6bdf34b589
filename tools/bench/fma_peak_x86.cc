// FMA chains for the peak measurement; each function carries its own target
// attribute, so this file is compiled for the baseline ISA.
#include <immintrin.h>

namespace aprt::bench {

__attribute__((target("avx512f"))) float fma_chains_avx512(long iterations)
#define VEC __m512
#define VSET1 _mm512_set1_ps
#define VFMA _mm512_fmadd_ps
#define VADD _mm512_add_ps
#define VSUM _mm512_reduce_add_ps
#include "tools/bench/fma_peak_chains.inl"
#undef VEC
#undef VSET1
#undef VFMA
#undef VADD
#undef VSUM

    static inline __attribute__((target("avx2,fma"))) float sum256(__m256 v) {
  float t[8];
  _mm256_storeu_ps(t, v);
  return t[0] + t[1] + t[2] + t[3] + t[4] + t[5] + t[6] + t[7];
}

__attribute__((target("avx2,fma"))) float fma_chains_avx2(long iterations)
#define VEC __m256
#define VSET1 _mm256_set1_ps
#define VFMA _mm256_fmadd_ps
#define VADD _mm256_add_ps
#define VSUM sum256
#include "tools/bench/fma_peak_chains.inl"

    float fma_chains_neon(long) {
  return 0.0f;
}

}  // namespace aprt::bench
