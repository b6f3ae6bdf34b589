// Dense NHWC convolution for few input channels (the stem): per output pixel,
// up to 4 vectors of output channels accumulate in registers; input values
// are broadcast. Weights are repacked at load to [KH][KW][Ci][Co]
// (f32_conv2d_pack_weights). Included inside an ISA namespace.

template <int NV>
static inline void conv_pixel(const Conv2dShape& s, const float* x, const float* wp,
                              const float* bias, const float* res, int act, float* out, int iy0,
                              int ix0, int c0, int cn) {
  const int Ci = s.in_c, Co = s.out_c;
  V acc[NV];
  int cnt[NV];
#pragma GCC unroll 4
  for (int j = 0; j < NV; ++j) {
    const int left = cn - j * kLanes;
    cnt[j] = left < 0 ? 0 : (left > kLanes ? kLanes : left);
    acc[j] = bias ? vload_n(bias + c0 + j * kLanes, cnt[j]) : vzero();
  }
  for (int ky = 0; ky < s.kernel_h; ++ky) {
    const int iy = iy0 + ky;
    if (iy < 0 || iy >= s.in_h) continue;
    for (int kx = 0; kx < s.kernel_w; ++kx) {
      const int ix = ix0 + kx;
      if (ix < 0 || ix >= s.in_w) continue;
      const float* xp = x + (size_t(iy) * s.in_w + ix) * Ci;
      const float* w = wp + size_t((ky * s.kernel_w + kx) * Ci) * Co + c0;
      for (int ci = 0; ci < Ci; ++ci) {
        const V xv = vset1(xp[ci]);
#pragma GCC unroll 4
        for (int j = 0; j < NV; ++j) {
          acc[j] = vfmadd(xv, vload_n(w + size_t(ci) * Co + j * kLanes, cnt[j]), acc[j]);
        }
      }
    }
  }
#pragma GCC unroll 4
  for (int j = 0; j < NV; ++j) {
    V v = act ? vact(acc[j], act) : acc[j];
    if (res) v = vadd(v, vload_n(res + c0 + j * kLanes, cnt[j]));
    vstore_n(out + c0 + j * kLanes, v, cnt[j]);
  }
}

// P consecutive output pixels of one row whose taps all lie inside the input
// row (no horizontal padding): each weight vector is loaded once for the P
// pixels, and the P x NV accumulators are independent FMA chains (one pixel
// alone is a 27-deep chain on the stem's 3 x 3 x 3 taps).
template <int NV, int P, bool kFull>
static inline void conv_pixels(const Conv2dShape& s, const float* x, const float* wp,
                               const float* bias, const float* res, int act, float* out, int iy0,
                               int ix0, int c0, int cn) {
  const int Ci = s.in_c, Co = s.out_c;
  const size_t xstep = size_t(s.stride_w) * Ci;
  V acc[P][NV];
  int cnt[NV];
#pragma GCC unroll 4
  for (int j = 0; j < NV; ++j) {
    const int left = cn - j * kLanes;
    cnt[j] = left < 0 ? 0 : (left > kLanes ? kLanes : left);
    const V b = !bias ? vzero()
                : kFull ? vload(bias + c0 + j * kLanes)
                        : vload_n(bias + c0 + j * kLanes, cnt[j]);
#pragma GCC unroll 4
    for (int p = 0; p < P; ++p) acc[p][j] = b;
  }
  for (int ky = 0; ky < s.kernel_h; ++ky) {
    const int iy = iy0 + ky;
    if (iy < 0 || iy >= s.in_h) continue;
    for (int kx = 0; kx < s.kernel_w; ++kx) {
      const float* xp = x + (size_t(iy) * s.in_w + ix0 + kx) * Ci;
      const float* w = wp + size_t((ky * s.kernel_w + kx) * Ci) * Co + c0;
      for (int ci = 0; ci < Ci; ++ci) {
        V wv[NV];
#pragma GCC unroll 4
        for (int j = 0; j < NV; ++j) {
          wv[j] = kFull ? vload(w + size_t(ci) * Co + j * kLanes)
                        : vload_n(w + size_t(ci) * Co + j * kLanes, cnt[j]);
        }
#pragma GCC unroll 4
        for (int p = 0; p < P; ++p) {
          const V xv = vset1(xp[p * xstep + ci]);
#pragma GCC unroll 4
          for (int j = 0; j < NV; ++j) acc[p][j] = vfmadd(xv, wv[j], acc[p][j]);
        }
      }
    }
  }
#pragma GCC unroll 4
  for (int p = 0; p < P; ++p) {
#pragma GCC unroll 4
    for (int j = 0; j < NV; ++j) {
      V v = act ? vact(acc[p][j], act) : acc[p][j];
      float* o = out + size_t(p) * Co + c0 + j * kLanes;
      if (kFull) {
        if (res) v = vadd(v, vload(res + size_t(p) * Co + c0 + j * kLanes));
        vstore(o, v);
      } else {
        if (res) v = vadd(v, vload_n(res + size_t(p) * Co + c0 + j * kLanes, cnt[j]));
        vstore_n(o, v, cnt[j]);
      }
    }
  }
}

// Output pixels [ox, ox + P) of row oy, channels [c0, c0 + cn) (cn <= 4 vectors).
template <int P>
static inline void conv_block(const Conv2dShape& s, const float* x, const float* wp,
                              const float* bias, const float* res, int act, float* out, int iy0,
                              int ix0, int c0, int cn) {
#define APRT_CONV_NV(NVV)                                                                   \
  if (cn == NVV * kLanes) {                                                                 \
    conv_pixels<NVV, P, true>(s, x, wp, bias, res, act, out, iy0, ix0, c0, cn);             \
  } else {                                                                                  \
    conv_pixels<NVV, P, false>(s, x, wp, bias, res, act, out, iy0, ix0, c0, cn);            \
  }
  if (cn <= kLanes) {
    APRT_CONV_NV(1)
  } else if (cn <= 2 * kLanes) {
    APRT_CONV_NV(2)
  } else {
    APRT_CONV_NV(4)
  }
#undef APRT_CONV_NV
}

static void conv_rows(const Conv2dShape& s, const float* x, const float* wp, const float* bias,
                      const float* residual, int act, float* y, int oy0, int oy1) {
  const int Co = s.out_c;
  constexpr int kBlock = 4 * kLanes;
  // Interior columns [ox_lo, ox_hi): every tap inside the input row.
  const int ox_lo = (s.pad_left + s.stride_w - 1) / s.stride_w;
  int ox_hi = (s.in_w - s.kernel_w + s.pad_left) >= 0
                  ? (s.in_w - s.kernel_w + s.pad_left) / s.stride_w + 1
                  : 0;
  ox_hi = ox_hi > s.out_w ? s.out_w : ox_hi;
  for (int oy = oy0; oy < oy1; ++oy) {
    const int iy0 = oy * s.stride_h - s.pad_top;
    for (int c0 = 0; c0 < Co; c0 += kBlock) {
      const int cn = Co - c0 < kBlock ? Co - c0 : kBlock;
      // Pixels per interior block: four, two for 4-vector channel blocks
      // (P x NV accumulators must leave registers for the weights).
      const int step = cn <= 2 * kLanes ? 4 : 2;
      int ox = 0;
      while (ox < s.out_w) {
        const size_t o = (size_t(oy) * s.out_w + ox) * Co;
        const int ix0 = ox * s.stride_w - s.pad_left;
        const float* res = residual ? residual + o : nullptr;
        if (ox >= ox_lo && ox + step <= ox_hi) {
          if (step == 4) {
            conv_block<4>(s, x, wp, bias, res, act, y + o, iy0, ix0, c0, cn);
          } else {
            conv_block<2>(s, x, wp, bias, res, act, y + o, iy0, ix0, c0, cn);
          }
          ox += step;
          continue;
        }
        if (cn <= kLanes) {
          conv_pixel<1>(s, x, wp, bias, res, act, y + o, iy0, ix0, c0, cn);
        } else if (cn <= 2 * kLanes) {
          conv_pixel<2>(s, x, wp, bias, res, act, y + o, iy0, ix0, c0, cn);
        } else {
          conv_pixel<4>(s, x, wp, bias, res, act, y + o, iy0, ix0, c0, cn);
        }
        ++ox;
      }
    }
  }
}
