// Depthwise NHWC convolution, vectorised over channels: per channel block the
// KH x KW weight vectors stay in registers while the row's output pixels
// stream through. Interior pixels run a fixed, unrolled kernel window, P
// pixels at a time; border pixels clip it. Included inside an ISA namespace
// (after vmath.inl).

// Output pixels whose windows are computed together: one pixel is one chain
// of KH x KW dependent FMAs (latency-bound: 9 taps x 4 cycles for one vector);
// P independent chains fill the FMA pipes. Sized so that the weights and the
// accumulators stay in registers (32 vector registers on AVX-512, 16 on AVX2
// and 32 on NEON, where kLanes is 4).
template <int KH, int KW>
constexpr int dwconv_pixels() {
  return KH * KW + 8 <= kVecRegisters - 4 ? 8 : 4;
}

// P interior output pixels from ox (whole window inside the input, full
// channel block): each pixel's sum in the same order as the single-pixel path.
template <int KH, int KW, int P>
static inline void dwconv_pixels_interior(const Conv2dShape& s, const float* x, const V (&wv)[KH][KW],
                                          V bv, int act, float* yrow, int iy0, int ky_lo,
                                          int ky_hi, int ox, int c0) {
  const int C = s.in_c;
  const int sw = s.stride_w;
  V acc[P];
#pragma GCC unroll 8
  for (int p = 0; p < P; ++p) acc[p] = bv;
  for (int ky = ky_lo; ky < ky_hi; ++ky) {
    const float* xr = x + (size_t(iy0 + ky) * s.in_w + size_t(ox * sw - s.pad_left)) * C + c0;
#pragma GCC unroll 5
    for (int kx = 0; kx < KW; ++kx) {
#pragma GCC unroll 8
      for (int p = 0; p < P; ++p)
        acc[p] = vfmadd(vload(xr + size_t(p * sw + kx) * C), wv[ky][kx], acc[p]);
    }
  }
#pragma GCC unroll 8
  for (int p = 0; p < P; ++p) {
    const V v = act ? vact(acc[p], act) : acc[p];
    vstore(yrow + size_t(ox + p) * C, v);
  }
}

template <int KH, int KW>
static void dwconv_rows_k(const Conv2dShape& s, const float* x, const float* w, const float* bias,
                          int act, float* y, int oy0, int oy1) {
  const int C = s.in_c;
  const int sw = s.stride_w;
  // Output columns whose whole window is inside the input.
  int ox_lo = (s.pad_left + sw - 1) / sw;
  int ox_hi = s.in_w - KW + s.pad_left >= 0 ? (s.in_w - KW + s.pad_left) / sw + 1 : 0;
  if (ox_hi > s.out_w) ox_hi = s.out_w;
  if (ox_lo > ox_hi) ox_lo = ox_hi;
  for (int oy = oy0; oy < oy1; ++oy) {
    const int iy0 = oy * s.stride_h - s.pad_top;
    const int ky_lo = iy0 < 0 ? -iy0 : 0;
    const int ky_hi = s.in_h - iy0 < KH ? s.in_h - iy0 : KH;
    for (int c0 = 0; c0 < C; c0 += kLanes) {
      const int cn = C - c0 < kLanes ? C - c0 : kLanes;
      const bool full = cn == kLanes;
      V wv[KH][KW];
#pragma GCC unroll 5
      for (int ky = 0; ky < KH; ++ky) {
#pragma GCC unroll 5
        for (int kx = 0; kx < KW; ++kx) {
          const float* wp = w + (ky * KW + kx) * C + c0;
          wv[ky][kx] = full ? vload(wp) : vload_n(wp, cn);
        }
      }
      const V bv = bias ? (full ? vload(bias + c0) : vload_n(bias + c0, cn)) : vzero();
      float* yrow = y + size_t(oy) * s.out_w * C + c0;
      constexpr int P = dwconv_pixels<KH, KW>();
      for (int ox = 0; ox < s.out_w; ++ox) {
        if (full && ox >= ox_lo && ox + P <= ox_hi) {
          dwconv_pixels_interior<KH, KW, P>(s, x, wv, bv, act, yrow, iy0, ky_lo, ky_hi, ox, c0);
          ox += P - 1;
          continue;
        }
        const int ix0 = ox * sw - s.pad_left;
        V acc = bv;
        if (ox >= ox_lo && ox < ox_hi && full) {
          for (int ky = ky_lo; ky < ky_hi; ++ky) {
            const float* xr = x + (size_t(iy0 + ky) * s.in_w + ix0) * C + c0;
#pragma GCC unroll 5
            for (int kx = 0; kx < KW; ++kx) acc = vfmadd(vload(xr + kx * C), wv[ky][kx], acc);
          }
        } else {
          const int kx_lo = ix0 < 0 ? -ix0 : 0;
          const int kx_hi = s.in_w - ix0 < KW ? s.in_w - ix0 : KW;
          for (int ky = ky_lo; ky < ky_hi && kx_lo < kx_hi; ++ky) {
            // From the first tap inside the image: a pointer left of the row
            // (ix0 < 0) would be out of the array even if never read.
            const float* xr = x + (size_t(iy0 + ky) * s.in_w + size_t(ix0 + kx_lo)) * C + c0;
            for (int kx = kx_lo; kx < kx_hi; ++kx) {
              const float* xp = xr + size_t(kx - kx_lo) * C;
              const V xv = full ? vload(xp) : vload_n(xp, cn);
              acc = vfmadd(xv, wv[ky][kx], acc);
            }
          }
        }
        if (act) acc = vact(acc, act);
        if (full) {
          vstore(yrow + size_t(ox) * C, acc);
        } else {
          vstore_n(yrow + size_t(ox) * C, acc, cn);
        }
      }
    }
  }
}

// Any kernel size: weights are reloaded from memory instead of registers.
static void dwconv_rows_any(const Conv2dShape& s, const float* x, const float* w,
                            const float* bias, int act, float* y, int oy0, int oy1) {
  const int C = s.in_c, KH = s.kernel_h, KW = s.kernel_w;
  for (int oy = oy0; oy < oy1; ++oy) {
    const int iy0 = oy * s.stride_h - s.pad_top;
    for (int ox = 0; ox < s.out_w; ++ox) {
      const int ix0 = ox * s.stride_w - s.pad_left;
      for (int c0 = 0; c0 < C; c0 += kLanes) {
        const int cn = C - c0 < kLanes ? C - c0 : kLanes;
        V acc = bias ? vload_n(bias + c0, cn) : vzero();
        for (int ky = 0; ky < KH; ++ky) {
          const int iy = iy0 + ky;
          if (iy < 0 || iy >= s.in_h) continue;
          for (int kx = 0; kx < KW; ++kx) {
            const int ix = ix0 + kx;
            if (ix < 0 || ix >= s.in_w) continue;
            acc = vfmadd(vload_n(x + (size_t(iy) * s.in_w + ix) * C + c0, cn),
                         vload_n(w + (ky * KW + kx) * C + c0, cn), acc);
          }
        }
        if (act) acc = vact(acc, act);
        vstore_n(y + (size_t(oy) * s.out_w + ox) * C + c0, acc, cn);
      }
    }
  }
}

static void dwconv_rows(const Conv2dShape& s, const float* x, const float* w, const float* bias,
                        int act, float* y, int oy0, int oy1) {
  if (s.kernel_h == 3 && s.kernel_w == 3) return dwconv_rows_k<3, 3>(s, x, w, bias, act, y, oy0, oy1);
  if (s.kernel_h == 5 && s.kernel_w == 5) return dwconv_rows_k<5, 5>(s, x, w, bias, act, y, oy0, oy1);
  dwconv_rows_any(s, x, w, bias, act, y, oy0, oy1);
}
