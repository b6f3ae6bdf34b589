// 8-lane float vectors on AVX2 + FMA. Same rules as vec_avx512.h (<immintrin.h>
// and <cstdint> included first, at global scope).

using V = __m256;
inline constexpr int kLanes = 8;
inline constexpr int kVecRegisters = 16;  // architectural vector registers

static inline V vzero() {
  return _mm256_setzero_ps();
}
static inline V vset1(float x) {
  return _mm256_set1_ps(x);
}
static inline V vload(const float* p) {
  return _mm256_loadu_ps(p);
}
static inline void vstore(float* p, V v) {
  _mm256_storeu_ps(p, v);
}
static inline __m256i vmask(int n) {
  return _mm256_cmpgt_epi32(_mm256_set1_epi32(n), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
}
static inline V vload_n(const float* p, int n) {
  return _mm256_maskload_ps(p, vmask(n));
}
static inline void vstore_n(float* p, V v, int n) {
  _mm256_maskstore_ps(p, vmask(n), v);
}
static inline V vfmadd(V a, V b, V c) {
  return _mm256_fmadd_ps(a, b, c);
}
static inline V vadd(V a, V b) {
  return _mm256_add_ps(a, b);
}
static inline V vsub(V a, V b) {
  return _mm256_sub_ps(a, b);
}
static inline V vmul(V a, V b) {
  return _mm256_mul_ps(a, b);
}
static inline V vdiv(V a, V b) {
  return _mm256_div_ps(a, b);
}
// 1/x to ~2 ulp: 12-bit estimate and one Newton step.
static inline V vrcp(V x) {
  const V r = _mm256_rcp_ps(x);
  return _mm256_fmadd_ps(r, _mm256_fnmadd_ps(x, r, _mm256_set1_ps(1.0f)), r);
}
static inline V vmax(V a, V b) {
  return _mm256_max_ps(a, b);
}
static inline V vmin(V a, V b) {
  return _mm256_min_ps(a, b);
}
static inline V vabs(V a) {
  return _mm256_and_ps(a, _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff)));
}
static inline V vsqrt(V a) {
  return _mm256_sqrt_ps(a);
}
static inline float vreduce_add(V v) {
  __m128 s = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  s = _mm_add_ps(s, _mm_movehl_ps(s, s));
  s = _mm_add_ss(s, _mm_movehdup_ps(s));
  return _mm_cvtss_f32(s);
}
static inline float vreduce_max(V v) {
  __m128 s = _mm_max_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  s = _mm_max_ps(s, _mm_movehl_ps(s, s));
  s = _mm_max_ss(s, _mm_movehdup_ps(s));
  return _mm_cvtss_f32(s);
}
// Lane tests without a horizontal reduction (a NaN lane is never <= c).
static inline bool vall_le(V a, float c) {
  return _mm256_movemask_ps(_mm256_cmp_ps(a, vset1(c), _CMP_LE_OQ)) == 0xFF;
}
static inline bool vany_ge(V a, float c) {
  return _mm256_movemask_ps(_mm256_cmp_ps(a, vset1(c), _CMP_GE_OQ)) != 0;
}
static inline V vfloor(V v) {
  return _mm256_round_ps(v, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
}
// kLanes bytes (unsigned) as floats.
static inline V vload_u8(const uint8_t* p) {
  return _mm256_cvtepi32_ps(
      _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p))));
}
static inline V vround(V v) {
  return _mm256_round_ps(v, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
}
static inline V vpow2i(V n) {
  const __m256i e = _mm256_add_epi32(_mm256_cvtps_epi32(n), _mm256_set1_epi32(127));
  return _mm256_castsi256_ps(_mm256_slli_epi32(e, 23));
}
// p * 2^n for integral n in [-126, 127].
static inline V vscale2(V p, V n) {
  return _mm256_mul_ps(p, vpow2i(n));
}
static inline V vcopysign(V magnitude, V sign) {
  const V s = _mm256_and_ps(sign, _mm256_castsi256_ps(_mm256_set1_epi32(INT32_MIN)));
  return _mm256_or_ps(vabs(magnitude), s);
}
