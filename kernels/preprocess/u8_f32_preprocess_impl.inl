// The fused camera-frame preprocessing (the training transform,
// kernels/preprocess/preprocess_image.h) for one ISA. Include inside an ISA
// namespace after the vector header.
//
// Per block of kLanes output pixels of a row: the four bilinear neighbours'
// raw channel bytes are collected into small lane arrays (scalar loads: no ISA
// here gathers bytes from computed offsets faster), then everything else runs
// in vectors -- YUV -> RGB exactly as yuv_to_rgb (in float: every
// intermediate is an integer below 2^24, and ">> 8" is floor(x / 256)), the
// bilinear blend, and the normalisation as one multiply-add (1 / (255 std),
// -mean / std), which replaces the reference's five divisions per value.
// Within a few ulp of the reference (the arithmetic order differs).

template <PixelFormat F>
static inline void gather_components(const ImageView& img, const uint8_t* row, const uint8_t* uv,
                                     int x, uint8_t* c0, uint8_t* c1, uint8_t* c2) {
  if constexpr (F == PixelFormat::kRgb24) {
    *c0 = row[3 * x];
    *c1 = row[3 * x + 1];
    *c2 = row[3 * x + 2];
  } else if constexpr (F == PixelFormat::kBgr24) {
    *c0 = row[3 * x + 2];
    *c1 = row[3 * x + 1];
    *c2 = row[3 * x];
  } else if constexpr (F == PixelFormat::kYuyv) {  // y u v
    const uint8_t* m = row + (x / 2) * 4;
    *c0 = m[(x & 1) ? 2 : 0];
    *c1 = m[1];
    *c2 = m[3];
  } else if constexpr (F == PixelFormat::kUyvy) {
    const uint8_t* m = row + (x / 2) * 4;
    *c0 = m[(x & 1) ? 3 : 1];
    *c1 = m[0];
    *c2 = m[2];
  } else if constexpr (F == PixelFormat::kNv12) {
    *c0 = row[x];
    *c1 = uv[(x / 2) * 2];
    *c2 = uv[(x / 2) * 2 + 1];
  } else {
    *c0 = *c1 = *c2 = row[x];
  }
  (void)img;
  (void)uv;
}

static inline V clamp_u8(V x) {
  return vmin(vmax(x, vzero()), vset1(255.0f));
}

// y u v (bytes as floats) -> r g b, as yuv_to_rgb computes them.
static inline void yuv_to_rgb_v(V y, V u, V v, V* r, V* g, V* b) {
  const V c = vmul(vsub(y, vset1(16.0f)), vset1(298.0f));
  const V d = vsub(u, vset1(128.0f));
  const V e = vsub(v, vset1(128.0f));
  const V half = vset1(128.0f), inv = vset1(1.0f / 256.0f);
  *r = clamp_u8(vfloor(vmul(vfmadd(vset1(409.0f), e, vadd(c, half)), inv)));
  *g = clamp_u8(
      vfloor(vmul(vfmadd(vset1(-208.0f), e, vfmadd(vset1(-100.0f), d, vadd(c, half))), inv)));
  *b = clamp_u8(vfloor(vmul(vfmadd(vset1(516.0f), d, vadd(c, half)), inv)));
}

template <PixelFormat F>
static void preprocess_rows_t(const PreprocessPlan& plan, const ImageView& img, float* out, int oy0,
                              int oy1) {
  constexpr bool kYuv =
      F == PixelFormat::kYuyv || F == PixelFormat::kUyvy || F == PixelFormat::kNv12;
  const PreprocessParams& p = plan.params;
  const int s = p.size, nc = p.channels;
  alignas(64) uint8_t raw[4][3][kLanes > 16 ? kLanes : 16] = {};  // neighbour, component, lane
  alignas(64) float res[3][kLanes];
  V scale[3], bias[3];
  for (int c = 0; c < nc; ++c) {
    scale[c] = vset1(1.0f / (255.0f * p.std[c]));
    bias[c] = vset1(-p.mean[c] / p.std[c]);
  }
  const uint8_t* uv_plane = img.data + size_t(img.height) * img.stride;
  for (int oy = oy0; oy < oy1; ++oy) {
    const int ya = plan.y0[oy], yb = plan.y1[oy];
    const uint8_t* rows[2] = {img.data + size_t(ya) * img.stride,
                              img.data + size_t(yb) * img.stride};
    const uint8_t* uvs[2] = {uv_plane + size_t(ya / 2) * img.stride,
                             uv_plane + size_t(yb / 2) * img.stride};
    const V wy = vset1(plan.wy[oy]), wy1 = vset1(1.0f - plan.wy[oy]);
    float* orow = out + size_t(oy) * s * nc;
    for (int ox0 = 0; ox0 < s; ox0 += kLanes) {
      const int n = s - ox0 < kLanes ? s - ox0 : kLanes;
      for (int j = 0; j < n; ++j) {
        const int xs[2] = {plan.x0[ox0 + j], plan.x1[ox0 + j]};
        for (int k = 0; k < 4; ++k) {  // a (ya, xa), b (ya, xb), c (yb, xa), d (yb, xb)
          gather_components<F>(img, rows[k >> 1], uvs[k >> 1], xs[k & 1], &raw[k][0][j],
                               &raw[k][1][j], &raw[k][2][j]);
        }
      }
      const V wx = vload_n(plan.wx + ox0, n);
      const V wx1 = vsub(vset1(1.0f), wx);
      V px[4][3];
      for (int k = 0; k < 4; ++k) {
        const V c0 = vload_u8(raw[k][0]);
        if constexpr (kYuv) {
          yuv_to_rgb_v(c0, vload_u8(raw[k][1]), vload_u8(raw[k][2]), &px[k][0], &px[k][1],
                       &px[k][2]);
        } else {
          px[k][0] = c0;
          px[k][1] = vload_u8(raw[k][1]);
          px[k][2] = vload_u8(raw[k][2]);
        }
      }
      for (int c = 0; c < nc; ++c) {
        const V top = vfmadd(px[1][c], wx, vmul(px[0][c], wx1));
        const V bot = vfmadd(px[3][c], wx, vmul(px[2][c], wx1));
        const V v = vfmadd(bot, wy, vmul(top, wy1));
        const V o = vfmadd(v, scale[c], bias[c]);
        if (nc == 1) {
          vstore_n(orow + ox0, o, n);
        } else {
          vstore(res[c], o);
        }
      }
      if (nc == 3) {
        float* dst = orow + size_t(ox0) * 3;
        for (int j = 0; j < n; ++j) {
          dst[3 * j] = res[0][j];
          dst[3 * j + 1] = res[1][j];
          dst[3 * j + 2] = res[2][j];
        }
      }
    }
  }
}

static void preprocess_rows(const PreprocessPlan& plan, const ImageView& img, float* out, int oy0,
                            int oy1) {
  switch (plan.format) {
    case PixelFormat::kRgb24:
      return preprocess_rows_t<PixelFormat::kRgb24>(plan, img, out, oy0, oy1);
    case PixelFormat::kBgr24:
      return preprocess_rows_t<PixelFormat::kBgr24>(plan, img, out, oy0, oy1);
    case PixelFormat::kYuyv: return preprocess_rows_t<PixelFormat::kYuyv>(plan, img, out, oy0, oy1);
    case PixelFormat::kUyvy: return preprocess_rows_t<PixelFormat::kUyvy>(plan, img, out, oy0, oy1);
    case PixelFormat::kNv12: return preprocess_rows_t<PixelFormat::kNv12>(plan, img, out, oy0, oy1);
    case PixelFormat::kGray8:
      return preprocess_rows_t<PixelFormat::kGray8>(plan, img, out, oy0, oy1);
  }
}
