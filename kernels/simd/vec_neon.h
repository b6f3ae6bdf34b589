// 4-lane float vectors on AArch64 Advanced SIMD (NEON). The including file has
// included <arm_neon.h> and <cstdint> at global scope; include only inside an
// ISA namespace (see vec_avx512.h).

using V = float32x4_t;
inline constexpr int kLanes = 4;
inline constexpr int kVecRegisters = 32;  // architectural vector registers

static inline V vzero() {
  return vdupq_n_f32(0.0f);
}
static inline V vset1(float x) {
  return vdupq_n_f32(x);
}
static inline V vload(const float* p) {
  return vld1q_f32(p);
}
static inline void vstore(float* p, V v) {
  vst1q_f32(p, v);
}
// First n lanes (0 <= n <= 4); never touches memory past p + n.
static inline V vload_n(const float* p, int n) {
  if (n >= kLanes) return vld1q_f32(p);
  float t[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  for (int i = 0; i < n; ++i) t[i] = p[i];
  return vld1q_f32(t);
}
static inline void vstore_n(float* p, V v, int n) {
  if (n >= kLanes) {
    vst1q_f32(p, v);
    return;
  }
  float t[4];
  vst1q_f32(t, v);
  for (int i = 0; i < n; ++i) p[i] = t[i];
}
static inline V vfmadd(V a, V b, V c) {
  return vfmaq_f32(c, a, b);
}
static inline V vadd(V a, V b) {
  return vaddq_f32(a, b);
}
static inline V vsub(V a, V b) {
  return vsubq_f32(a, b);
}
static inline V vmul(V a, V b) {
  return vmulq_f32(a, b);
}
static inline V vdiv(V a, V b) {
  return vdivq_f32(a, b);
}
// 1/x: estimate and two Newton steps (vrecpsq_f32 computes 2 - x r).
static inline V vrcp(V x) {
  V r = vrecpeq_f32(x);
  r = vmulq_f32(r, vrecpsq_f32(x, r));
  return vmulq_f32(r, vrecpsq_f32(x, r));
}
static inline V vmax(V a, V b) {
  return vmaxq_f32(a, b);
}
static inline V vmin(V a, V b) {
  return vminq_f32(a, b);
}
static inline V vabs(V a) {
  return vabsq_f32(a);
}
static inline V vsqrt(V a) {
  return vsqrtq_f32(a);
}
static inline float vreduce_add(V v) {
  return vaddvq_f32(v);
}
static inline float vreduce_max(V v) {
  return vmaxvq_f32(v);
}
// Lane tests without a horizontal sum (a NaN lane is never <= c).
static inline bool vall_le(V a, float c) {
  return vminvq_u32(vcleq_f32(a, vdupq_n_f32(c))) != 0;
}
static inline bool vany_ge(V a, float c) {
  return vmaxvq_u32(vcgeq_f32(a, vdupq_n_f32(c))) != 0;
}
static inline V vfloor(V v) {
  return vrndmq_f32(v);
}
// kLanes bytes (unsigned) as floats.
static inline V vload_u8(const uint8_t* p) {
  const uint8x8_t b = vcreate_u8(uint64_t(p[0]) | uint64_t(p[1]) << 8 | uint64_t(p[2]) << 16 |
                                 uint64_t(p[3]) << 24);
  return vcvtq_f32_u32(vmovl_u16(vget_low_u16(vmovl_u8(b))));
}
static inline V vround(V v) {
  return vrndnq_f32(v);
}
static inline V vpow2i(V n) {
  const int32x4_t e = vaddq_s32(vcvtq_s32_f32(n), vdupq_n_s32(127));
  return vreinterpretq_f32_s32(vshlq_n_s32(e, 23));
}
static inline V vscale2(V p, V n) {
  return vmulq_f32(p, vpow2i(n));
}
static inline V vcopysign(V magnitude, V sign) {
  const uint32x4_t mask = vdupq_n_u32(0x80000000u);
  return vbslq_f32(mask, sign, vabsq_f32(magnitude));
}
