// int8 depthwise NHWC convolution (issue #4), vectorised over channels.
// Included inside an ISA namespace after vec_<isa>.h and vmath.inl.
//
// Exact in float: every product (x - zero) * w is an integer of magnitude at
// most 255 * 127, and a window of at most kMaxQDwTaps taps keeps every partial
// sum below 2^24, so the fused multiply-adds below compute the int32
// accumulator of qu8s8_dwconv2d__ref bit for bit. The epilogue is the same
// single FMA (acc * mult + bias) as every int8 kernel, then the activation.
// The weights' sum (for the zero-point correction) is exact too: at most
// kMaxQDwTaps * 127.

static inline V vload_u8_n(const uint8_t* p, int n) {  // n < kLanes bytes, zero-filled
  alignas(64) uint8_t tmp[64] = {};
  for (int i = 0; i < n; ++i) tmp[i] = p[i];
  return vload_u8(tmp);
}

// Fixed KH x KW: per channel block the weights, their zero-point correction,
// the multiplier and bias stay in registers while the row's pixels stream.
// Interior pixels: acc = sum x * w - zero * sum w (both sums exact); border
// pixels subtract the zero point per tap inside the image.
template <int KH, int KW>
static void qdwconv_rows_k(const QDwConvArgs& a, int oy0, int oy1) {
  const Conv2dShape& s = a.shape;
  const int C = s.in_c, sw = s.stride_w;
  const V zero = vset1(float(a.a_zero));
  const int act = int(a.act);
  int ox_lo = (s.pad_left + sw - 1) / sw;
  int ox_hi = s.in_w - KW + s.pad_left >= 0 ? (s.in_w - KW + s.pad_left) / sw + 1 : 0;
  if (ox_hi > s.out_w) ox_hi = s.out_w;
  if (ox_lo > ox_hi) ox_lo = ox_hi;
  for (int oy = oy0; oy < oy1; ++oy) {
    const int iy0 = oy * s.stride_h - s.pad_top;
    const int ky_lo = iy0 < 0 ? -iy0 : 0;
    const int ky_hi = s.in_h - iy0 < KH ? s.in_h - iy0 : KH;
    const bool rows_inside = ky_lo == 0 && ky_hi == KH;
    for (int c0 = 0; c0 < C; c0 += kLanes) {
      const int cn = C - c0 < kLanes ? C - c0 : kLanes;
      const bool full = cn == kLanes;
      V wv[KH][KW];
      V wsum = vzero();
#pragma GCC unroll 5
      for (int ky = 0; ky < KH; ++ky) {
#pragma GCC unroll 5
        for (int kx = 0; kx < KW; ++kx) {
          const float* wp = a.w + (ky * KW + kx) * C + c0;
          wv[ky][kx] = full ? vload(wp) : vload_n(wp, cn);
          wsum = vadd(wsum, wv[ky][kx]);
        }
      }
      const V wz = vmul(zero, wsum);
      const V m = full ? vload(a.mult + c0) : vload_n(a.mult + c0, cn);
      const V b = full ? vload(a.bias + c0) : vload_n(a.bias + c0, cn);
      float* yrow = a.y + size_t(oy) * s.out_w * C + c0;
      for (int ox = 0; ox < s.out_w; ++ox) {
        const int ix0 = ox * sw - s.pad_left;
        V acc = vzero();
        if (rows_inside && ox >= ox_lo && ox < ox_hi && full) {
#pragma GCC unroll 5
          for (int ky = 0; ky < KH; ++ky) {
            const uint8_t* xr = a.x + (size_t(iy0 + ky) * s.in_w + ix0) * C + c0;
#pragma GCC unroll 5
            for (int kx = 0; kx < KW; ++kx) acc = vfmadd(vload_u8(xr + kx * C), wv[ky][kx], acc);
          }
          acc = vsub(acc, wz);
        } else {
          const int kx_lo = ix0 < 0 ? -ix0 : 0;
          const int kx_hi = s.in_w - ix0 < KW ? s.in_w - ix0 : KW;
          for (int ky = ky_lo; ky < ky_hi; ++ky) {
            for (int kx = kx_lo; kx < kx_hi; ++kx) {
              const uint8_t* xp = a.x + (size_t(iy0 + ky) * s.in_w + size_t(ix0 + kx)) * C + c0;
              const V xv = full ? vload_u8(xp) : vload_u8_n(xp, cn);
              acc = vfmadd(vsub(xv, zero), wv[ky][kx], acc);
            }
          }
        }
        V y = vfmadd(acc, m, b);
        if (act) y = vact(y, act);
        if (full) {
          vstore(yrow + size_t(ox) * C, y);
        } else {
          vstore_n(yrow + size_t(ox) * C, y, cn);
        }
      }
    }
  }
}

// Any kernel size: per pixel, taps inside the image only.
static void qdwconv_rows_any(const QDwConvArgs& a, int oy0, int oy1) {
  const Conv2dShape& s = a.shape;
  const int C = s.in_c, KH = s.kernel_h, KW = s.kernel_w;
  const V zero = vset1(float(a.a_zero));
  const int act = int(a.act);
  for (int oy = oy0; oy < oy1; ++oy) {
    const int iy0 = oy * s.stride_h - s.pad_top;
    const int ky_lo = iy0 < 0 ? -iy0 : 0;
    const int ky_hi = s.in_h - iy0 < KH ? s.in_h - iy0 : KH;
    for (int ox = 0; ox < s.out_w; ++ox) {
      const int ix0 = ox * s.stride_w - s.pad_left;
      const int kx_lo = ix0 < 0 ? -ix0 : 0;
      const int kx_hi = s.in_w - ix0 < KW ? s.in_w - ix0 : KW;
      float* yp = a.y + (size_t(oy) * s.out_w + ox) * C;
      for (int c0 = 0; c0 < C; c0 += kLanes) {
        const int cn = C - c0 < kLanes ? C - c0 : kLanes;
        const bool full = cn == kLanes;
        V acc = vzero();
        for (int ky = ky_lo; ky < ky_hi; ++ky) {
          for (int kx = kx_lo; kx < kx_hi; ++kx) {
            const uint8_t* xp = a.x + (size_t(iy0 + ky) * s.in_w + size_t(ix0 + kx)) * C + c0;
            const float* wp = a.w + (ky * KW + kx) * C + c0;
            const V xv = full ? vload_u8(xp) : vload_u8_n(xp, cn);
            const V wv = full ? vload(wp) : vload_n(wp, cn);
            acc = vfmadd(vsub(xv, zero), wv, acc);
          }
        }
        const V m = full ? vload(a.mult + c0) : vload_n(a.mult + c0, cn);
        const V b = full ? vload(a.bias + c0) : vload_n(a.bias + c0, cn);
        V y = vfmadd(acc, m, b);
        if (act) y = vact(y, act);
        if (full) {
          vstore(yp + c0, y);
        } else {
          vstore_n(yp + c0, y, cn);
        }
      }
    }
  }
}

static void qdwconv_rows(const QDwConvArgs& a, int oy0, int oy1) {
  const int kh = a.shape.kernel_h, kw = a.shape.kernel_w;
  if (kh == 3 && kw == 3) return qdwconv_rows_k<3, 3>(a, oy0, oy1);
  if (kh == 5 && kw == 5) return qdwconv_rows_k<5, 5>(a, oy0, oy1);
  qdwconv_rows_any(a, oy0, oy1);
}
