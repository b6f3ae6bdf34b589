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

static void conv_rows(const Conv2dShape& s, const float* x, const float* wp, const float* bias,
                      const float* residual, int act, float* y, int oy0, int oy1) {
  const int Co = s.out_c;
  constexpr int kBlock = 4 * kLanes;
  for (int oy = oy0; oy < oy1; ++oy) {
    for (int ox = 0; ox < s.out_w; ++ox) {
      const size_t o = (size_t(oy) * s.out_w + ox) * Co;
      const int iy0 = oy * s.stride_h - s.pad_top, ix0 = ox * s.stride_w - s.pad_left;
      for (int c0 = 0; c0 < Co; c0 += kBlock) {
        const int cn = Co - c0 < kBlock ? Co - c0 : kBlock;
        const float* res = residual ? residual + o : nullptr;
        if (cn <= kLanes) {
          conv_pixel<1>(s, x, wp, bias, res, act, y + o, iy0, ix0, c0, cn);
        } else if (cn <= 2 * kLanes) {
          conv_pixel<2>(s, x, wp, bias, res, act, y + o, iy0, ix0, c0, cn);
        } else {
          conv_pixel<4>(s, x, wp, bias, res, act, y + o, iy0, ix0, c0, cn);
        }
      }
    }
  }
}
