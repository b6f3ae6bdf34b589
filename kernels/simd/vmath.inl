// Vector math on top of a vec_*.h header (V, vset1, vfmadd, ...): exp, sigmoid,
// erf, and the activations. Included inside an ISA namespace.
//
// exp: Cody-Waite range reduction by ln 2 and a degree-6 polynomial (Cephes
// coefficients), about 2 ulp on [-87.3, 88]; inputs are clamped to that range
// (below it the result is 1.2e-38 instead of a denormal or zero).
// erf: Abramowitz & Stegun 7.1.26, absolute error <= 1.5e-7, which is below
// GELU's float rounding at every magnitude that matters; its exponential is
// the base-2 one (vexp2_bounded).

static inline V vexp(V x) {
  // Clamped so that 2^n stays a normal float: n in [-126, 127].
  x = vmin(vmax(x, vset1(-87.33654f)), vset1(88.0f));
  const V n = vround(vmul(x, vset1(1.44269504088896341f)));
  V r = vfmadd(n, vset1(-0.693359375f), x);
  r = vfmadd(n, vset1(2.12194440e-4f), r);
  V p = vset1(1.9875691500e-4f);
  p = vfmadd(p, r, vset1(1.3981999507e-3f));
  p = vfmadd(p, r, vset1(8.3334519073e-3f));
  p = vfmadd(p, r, vset1(4.1665795894e-2f));
  p = vfmadd(p, r, vset1(1.6666665459e-1f));
  p = vfmadd(p, r, vset1(5.0000001201e-1f));
  p = vfmadd(vmul(p, r), r, vadd(r, vset1(1.0f)));
  return vscale2(p, n);
}

// 2^x by x = n + r and a degree-5 minimax polynomial of 2^r; p * 2^n by
// vscale2. The caller bounds x to [-125, 126], where 2^n and the result are
// normal floats on every ISA. Cheaper than vexp by the range reduction: the
// callers fold log2(e) into a multiply they do anyway.
#ifdef APRT_VEC_HAS_FRAC_FLOOR
// n = floor(x), r = x - n in [0, 1) in one instruction, and vscale2 floors x
// itself: two operations fewer than rounding and subtracting (the attention's
// exponent pass is ~15 % of its vector operations). Relative error 1.5e-7.
// Above 128 the result saturates to +inf (vscalefps), so callers that catch
// an infinite sum need no upper clamp (kExp2SaturatesHigh).
inline constexpr bool kExp2SaturatesHigh = true;
static inline V vexp2_bounded(V x) {
  const V r = vfrac_floor(x);
  V p = vset1(1.8775556e-3f);
  p = vfmadd(p, r, vset1(8.9893304e-3f));
  p = vfmadd(p, r, vset1(5.5826392e-2f));
  p = vfmadd(p, r, vset1(2.4015357e-1f));
  p = vfmadd(p, r, vset1(6.9315308e-1f));
  p = vfmadd(p, r, vset1(0.99999994f));
  return vscale2(p, x);
}
#else
// n = round(x), r = x - n exact in [-0.5, 0.5]; relative error 2.4e-7 (4 ulp).
// 2^n is built from its exponent bits: x above 127 gives garbage, not +inf.
inline constexpr bool kExp2SaturatesHigh = false;
static inline V vexp2_bounded(V x) {
  const V n = vround(x);
  const V r = vsub(x, n);
  V p = vset1(1.3276472e-3f);
  p = vfmadd(p, r, vset1(9.6755410e-3f));
  p = vfmadd(p, r, vset1(5.5507131e-2f));
  p = vfmadd(p, r, vset1(2.4022120e-1f));
  p = vfmadd(p, r, vset1(6.9314694e-1f));
  p = vfmadd(p, r, vset1(1.0000001f));
  return vscale2(p, n);
}
#endif

// 2^x for x <= 0 (a softmax argument once the row maximum is subtracted):
// clamped below at -125, so a -inf argument (a padded key) gives 2^-125, not
// NaN, and 2^-125 is below the rounding of any row sum it joins. A NaN stays
// NaN (x is max's second operand: x86 returns it when NaN; NEON propagates).
static inline V vexp2_nonpos(V x) {
  return vexp2_bounded(vmax(vset1(-125.0f), x));
}

// 1 / (1 + e^-x) with e^-x = 2^(-x log2 e), clamped to [2^-125, 2^126]: for
// x beyond about +-87 the result is 1 or ~1e-38 instead of a denormal.
// Five fewer dependent operations than through vexp, which matters where a
// SiLU ends every output vector (stem, depthwise and expansion convolutions).
static inline V vsigmoid(V x) {
  V a = vmul(x, vset1(-1.44269504088896341f));
  a = vmin(vmax(a, vset1(-125.0f)), vset1(126.0f));
  return vrcp(vadd(vset1(1.0f), vexp2_bounded(a)));
}

static inline V verf(V x) {
  const V a = vabs(x);
  const V t = vrcp(vfmadd(a, vset1(0.3275911f), vset1(1.0f)));
  V p = vset1(1.061405429f);
  p = vfmadd(p, t, vset1(-1.453152027f));
  p = vfmadd(p, t, vset1(1.421413741f));
  p = vfmadd(p, t, vset1(-0.284496736f));
  p = vfmadd(p, t, vset1(0.254829592f));
  p = vmul(p, t);
  // e^(-a^2) as 2^(-a^2 log2 e), clamped at 2^-125 (erf is 1 to float
  // precision long before, at a ~ 4): the base-2 exponential needs no
  // Cody-Waite reduction, ~6 operations fewer per vector than vexp (GELU
  // ends every transformer feed-forward's first product).
  const V e2 = vmax(vmul(a, vmul(a, vset1(-1.44269504088896341f))), vset1(-125.0f));
  const V y = vsub(vset1(1.0f), vmul(p, vexp2_bounded(e2)));
  return vcopysign(y, x);
}

// act codes as kernels::Act: 0 none, 1 SiLU, 2 GELU, 3 sigmoid, 4 ReLU.
static inline V vact(V x, int act) {
  switch (act) {
    case 1: return vmul(x, vsigmoid(x));
    case 2:
      return vmul(vmul(x, vset1(0.5f)),
                  vadd(vset1(1.0f), verf(vmul(x, vset1(0.70710678118654752f)))));
    case 3: return vsigmoid(x);
    case 4: return vmax(x, vzero());
    default: return x;
  }
}
