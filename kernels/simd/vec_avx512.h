// 16-lane float vectors on AVX-512F. The including file has included
// <immintrin.h> and <cstdint> at global scope. Include only inside a translation unit
// compiled for AVX-512 (the *__simd.cc files, kernels/simd/isa.h), inside that ISA's namespace,
// so no inline function from here is ever merged with another ISA's.

using V = __m512;
inline constexpr int kLanes = 16;
inline constexpr int kVecRegisters = 32;  // architectural vector registers

static inline V vzero() {
  return _mm512_setzero_ps();
}
static inline V vset1(float x) {
  return _mm512_set1_ps(x);
}
static inline V vload(const float* p) {
  return _mm512_loadu_ps(p);
}
static inline void vstore(float* p, V v) {
  _mm512_storeu_ps(p, v);
}
static inline __mmask16 vmask(int n) {
  return static_cast<__mmask16>((1u << n) - 1u);
}
// First n lanes (0 < n <= kLanes); the rest are zero. Never reads past p + n.
static inline V vload_n(const float* p, int n) {
  return _mm512_maskz_loadu_ps(vmask(n), p);
}
static inline void vstore_n(float* p, V v, int n) {
  _mm512_mask_storeu_ps(p, vmask(n), v);
}
static inline V vfmadd(V a, V b, V c) {
  return _mm512_fmadd_ps(a, b, c);
}
static inline V vadd(V a, V b) {
  return _mm512_add_ps(a, b);
}
static inline V vsub(V a, V b) {
  return _mm512_sub_ps(a, b);
}
static inline V vmul(V a, V b) {
  return _mm512_mul_ps(a, b);
}
static inline V vdiv(V a, V b) {
  return _mm512_div_ps(a, b);
}
// 1/x to ~1 ulp: 14-bit estimate and one Newton step (a division costs ~16 cycles).
static inline V vrcp(V x) {
  const V r = _mm512_rcp14_ps(x);
  return _mm512_fmadd_ps(r, _mm512_fnmadd_ps(x, r, _mm512_set1_ps(1.0f)), r);
}
static inline V vmax(V a, V b) {
  return _mm512_max_ps(a, b);
}
static inline V vmin(V a, V b) {
  return _mm512_min_ps(a, b);
}
static inline V vabs(V a) {
  return _mm512_abs_ps(a);
}
static inline V vsqrt(V a) {
  return _mm512_sqrt_ps(a);
}
static inline float vreduce_add(V v) {
  return _mm512_reduce_add_ps(v);
}
static inline float vreduce_max(V v) {
  return _mm512_reduce_max_ps(v);
}
// Lane tests without a horizontal reduction (a NaN lane is never <= c).
static inline bool vall_le(V a, float c) {
  return _mm512_cmp_ps_mask(a, vset1(c), _CMP_LE_OQ) == 0xFFFF;
}
static inline bool vany_ge(V a, float c) {
  return _mm512_cmp_ps_mask(a, vset1(c), _CMP_GE_OQ) != 0;
}
static inline V vfloor(V v) {
  return _mm512_roundscale_ps(v, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
}
// kLanes bytes (unsigned) as floats.
static inline V vload_u8(const uint8_t* p) {
  return _mm512_cvtepi32_ps(
      _mm512_cvtepu8_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p))));
}
static inline V vround(V v) {
  return _mm512_roundscale_ps(v, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
}
// p * 2^floor(n) (vscalefps: one instruction, exact; n integral elsewhere).
static inline V vscale2(V p, V n) {
  return _mm512_scalef_ps(p, n);
}
// x - floor(x), exactly, in [0, 1): vreduceps (AVX512DQ). With vscale2,
// which floors its exponent operand itself, 2^x is p(x - floor x) *
// 2^floor(x) without a separate rounding and subtraction (vexp2_bounded).
#define APRT_VEC_HAS_FRAC_FLOOR 1
static inline V vfrac_floor(V x) {
  return _mm512_reduce_ps(x, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
}
// 2^n for integral n in [-126, 127].
static inline V vpow2i(V n) {
  const __m512i e = _mm512_add_epi32(_mm512_cvtps_epi32(n), _mm512_set1_epi32(127));
  return _mm512_castsi512_ps(_mm512_slli_epi32(e, 23));
}
static inline V vcopysign(V magnitude, V sign) {
  const __m512i s = _mm512_and_si512(_mm512_castps_si512(sign), _mm512_set1_epi32(INT32_MIN));
  return _mm512_castsi512_ps(_mm512_or_si512(_mm512_castps_si512(vabs(magnitude)), s));
}
