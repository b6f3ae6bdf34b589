// Row-wise and element-wise kernels: LayerNorm, add, activation,
// squeeze-excite. Included inside an ISA namespace (after vmath.inl).

static const float kOnes[16] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};

// R rows of a width that is a multiple of two vectors, interleaved: one row is
// a chain of dependent steps (sum, horizontal reduce, mean, squares, reduce,
// square root, divide) that leaves the pipes idle; R rows fill them. Each
// row's arithmetic is the one-row loop's below, operation for operation.
template <int R>
static inline void layernorm_rows_x(int n, const float* x, const float* gamma, const float* beta,
                                    float eps, float* y, int r) {
  V s0[R], s1[R];
#pragma GCC unroll 4
  for (int k = 0; k < R; ++k) s0[k] = s1[k] = vzero();
  for (int i = 0; i < n; i += 2 * kLanes) {
#pragma GCC unroll 4
    for (int k = 0; k < R; ++k) {
      const float* xr = x + size_t(r + k) * n;
      s0[k] = vadd(s0[k], vload(xr + i));
      s1[k] = vadd(s1[k], vload(xr + i + kLanes));
    }
  }
  V m[R], q0[R], q1[R];
#pragma GCC unroll 4
  for (int k = 0; k < R; ++k) {
    m[k] = vset1(vreduce_add(vadd(s0[k], s1[k])) / float(n));
    q0[k] = q1[k] = vzero();
  }
  for (int i = 0; i < n; i += 2 * kLanes) {
#pragma GCC unroll 4
    for (int k = 0; k < R; ++k) {
      const float* xr = x + size_t(r + k) * n;
      const V d0 = vsub(vload(xr + i), m[k]), d1 = vsub(vload(xr + i + kLanes), m[k]);
      q0[k] = vfmadd(d0, d0, q0[k]);
      q1[k] = vfmadd(d1, d1, q1[k]);
    }
  }
  V inv[R];
#pragma GCC unroll 4
  for (int k = 0; k < R; ++k) {
    const float var = vreduce_add(vadd(q0[k], q1[k])) / float(n);
    inv[k] = vset1(1.0f / __builtin_sqrtf(var + eps));
  }
  for (int i = 0; i < n; i += kLanes) {
    const V g = vload(gamma + i), b = vload(beta + i);
#pragma GCC unroll 4
    for (int k = 0; k < R; ++k) {
      const V v = vmul(vsub(vload(x + size_t(r + k) * n + i), m[k]), inv[k]);
      vstore(y + size_t(r + k) * n + i, vfmadd(v, g, b));
    }
  }
}

static void layernorm_rows(int n, const float* x, const float* gamma, const float* beta,
                           float eps, float* y, int r0, int r1) {
  if (n % (2 * kLanes) == 0) {
    for (; r0 + 4 <= r1; r0 += 4) layernorm_rows_x<4>(n, x, gamma, beta, eps, y, r0);
  }
  for (int r = r0; r < r1; ++r) {
    const float* xr = x + size_t(r) * n;
    float* yr = y + size_t(r) * n;
    V s0 = vzero(), s1 = vzero();
    int i = 0;
    for (; i + 2 * kLanes <= n; i += 2 * kLanes) {
      s0 = vadd(s0, vload(xr + i));
      s1 = vadd(s1, vload(xr + i + kLanes));
    }
    for (; i < n; i += kLanes) s0 = vadd(s0, vload_n(xr + i, n - i < kLanes ? n - i : kLanes));
    const float mean = vreduce_add(vadd(s0, s1)) / float(n);
    const V m = vset1(mean);
    V q0 = vzero(), q1 = vzero();
    i = 0;
    for (; i + 2 * kLanes <= n; i += 2 * kLanes) {
      const V d0 = vsub(vload(xr + i), m), d1 = vsub(vload(xr + i + kLanes), m);
      q0 = vfmadd(d0, d0, q0);
      q1 = vfmadd(d1, d1, q1);
    }
    for (; i < n; i += kLanes) {
      const int c = n - i < kLanes ? n - i : kLanes;
      // Lanes past the row end would hold -mean: zero them before squaring.
      const V d = vmul(vsub(vload_n(xr + i, c), m), vload_n(kOnes, c));
      q0 = vfmadd(d, d, q0);
    }
    const float var = vreduce_add(vadd(q0, q1)) / float(n);
    const V inv = vset1(1.0f / __builtin_sqrtf(var + eps));
    for (i = 0; i < n; i += kLanes) {
      const int c = n - i < kLanes ? n - i : kLanes;
      const V v = vmul(vsub(vload_n(xr + i, c), m), inv);
      vstore_n(yr + i, vfmadd(v, vload_n(gamma + i, c), vload_n(beta + i, c)), c);
    }
  }
}

static void add_range(const float* a, const float* b, float* y, size_t i0, size_t i1) {
  size_t i = i0;
  for (; i + kLanes <= i1; i += kLanes) vstore(y + i, vadd(vload(a + i), vload(b + i)));
  if (i < i1) {
    const int c = int(i1 - i);
    vstore_n(y + i, vadd(vload_n(a + i, c), vload_n(b + i, c)), c);
  }
}

static void softmax_rows(int n, float* x, int r0, int r1) {
  for (int r = r0; r < r1; ++r) {
    float* xr = x + size_t(r) * n;
    V mx = vset1(-__builtin_inff());
    int i = 0;
    for (; i + kLanes <= n; i += kLanes) mx = vmax(mx, vload(xr + i));
    float m = vreduce_max(mx);
    for (; i < n; ++i) m = xr[i] > m ? xr[i] : m;
    const V mv = vset1(m);
    V sum = vzero();
    for (i = 0; i < n; i += kLanes) {
      const int c = n - i < kLanes ? n - i : kLanes;
      const V e = vmul(vexp(vsub(vload_n(xr + i, c), mv)), vload_n(kOnes, c));
      vstore_n(xr + i, e, c);
      sum = vadd(sum, e);
    }
    const V inv = vset1(1.0f / vreduce_add(sum));
    for (i = 0; i < n; i += kLanes) {
      const int c = n - i < kLanes ? n - i : kLanes;
      vstore_n(xr + i, vmul(vload_n(xr + i, c), inv), c);
    }
  }
}

static void activation_range(int act, const float* x, float* y, size_t i0, size_t i1) {
  size_t i = i0;
  for (; i + kLanes <= i1; i += kLanes) vstore(y + i, vact(vload(x + i), act));
  if (i < i1) {
    const int c = int(i1 - i);
    vstore_n(y + i, vact(vload_n(x + i, c), act), c);
  }
}

// Squeeze-excite, gate part: mean over pixels -> FC1 + SiLU -> FC2 + sigmoid.
// w2t is W2 transposed at load ([Cr][C]). scratch: C + Cr floats; writes the
// gate (C floats) to gate.
static void se_gate(int pixels, int C, int Cr, const float* x, const float* w1, const float* b1,
                    const float* w2t, const float* b2, float* gate, float* scratch) {
  float* mean = scratch;
  float* red = scratch + C;
  const V inv = vset1(1.0f / float(pixels));
  for (int c0 = 0; c0 < C; c0 += kLanes) {
    const int cn = C - c0 < kLanes ? C - c0 : kLanes;
    V s = vzero();
    for (int p = 0; p < pixels; ++p) s = vadd(s, vload_n(x + size_t(p) * C + c0, cn));
    vstore_n(mean + c0, vmul(s, inv), cn);
  }
  for (int r = 0; r < Cr; ++r) {
    V s = vzero();
    for (int c0 = 0; c0 < C; c0 += kLanes) {
      const int cn = C - c0 < kLanes ? C - c0 : kLanes;
      s = vfmadd(vload_n(w1 + size_t(r) * C + c0, cn), vload_n(mean + c0, cn), s);
    }
    red[r] = vreduce_add(s) + b1[r];
  }
  for (int r0 = 0; r0 < Cr; r0 += kLanes) {
    const int cn = Cr - r0 < kLanes ? Cr - r0 : kLanes;
    vstore_n(red + r0, vact(vload_n(red + r0, cn), 1), cn);
  }
  for (int c0 = 0; c0 < C; c0 += kLanes) {
    const int cn = C - c0 < kLanes ? C - c0 : kLanes;
    V s = vload_n(b2 + c0, cn);
    for (int r = 0; r < Cr; ++r) s = vfmadd(vset1(red[r]), vload_n(w2t + size_t(r) * C + c0, cn), s);
    vstore_n(gate + c0, vsigmoid(s), cn);
  }
}

// y[p][c] = x[p][c] * gate[c] for pixels [p0, p1).
static void se_scale(int C, const float* x, const float* gate, float* y, int p0, int p1) {
  for (int p = p0; p < p1; ++p) {
    const float* xp = x + size_t(p) * C;
    float* yp = y + size_t(p) * C;
    int c0 = 0;
    for (; c0 + kLanes <= C; c0 += kLanes) vstore(yp + c0, vmul(vload(xp + c0), vload(gate + c0)));
    if (c0 < C) {
      const int cn = C - c0;
      vstore_n(yp + c0, vmul(vload_n(xp + c0, cn), vload_n(gate + c0, cn)), cn);
    }
  }
}
