// 16 independent FMA chains on vector type VEC (VFMA, VSET1, VADD, VSUM given).
{
  volatile float seed = 1.0f;
  VEC a0 = VSET1(seed), a1 = VSET1(seed + 1), a2 = VSET1(seed + 2), a3 = VSET1(seed + 3);
  VEC a4 = VSET1(seed + 4), a5 = VSET1(seed + 5), a6 = VSET1(seed + 6), a7 = VSET1(seed + 7);
  VEC a8 = VSET1(seed + 8), a9 = VSET1(seed + 9), a10 = VSET1(seed + 10), a11 = VSET1(seed + 11);
  VEC a12 = VSET1(seed + 12), a13 = VSET1(seed + 13), a14 = VSET1(seed + 14), a15 = VSET1(seed + 15);
  const VEC b = VSET1(0.9999999f), c = VSET1(1e-7f);
  for (long i = 0; i < iterations; ++i) {
    a0 = VFMA(a0, b, c); a1 = VFMA(a1, b, c); a2 = VFMA(a2, b, c); a3 = VFMA(a3, b, c);
    a4 = VFMA(a4, b, c); a5 = VFMA(a5, b, c); a6 = VFMA(a6, b, c); a7 = VFMA(a7, b, c);
    a8 = VFMA(a8, b, c); a9 = VFMA(a9, b, c); a10 = VFMA(a10, b, c); a11 = VFMA(a11, b, c);
    a12 = VFMA(a12, b, c); a13 = VFMA(a13, b, c); a14 = VFMA(a14, b, c); a15 = VFMA(a15, b, c);
  }
  const VEC s = VADD(VADD(VADD(VADD(a0, a1), VADD(a2, a3)), VADD(VADD(a4, a5), VADD(a6, a7))),
                     VADD(VADD(VADD(a8, a9), VADD(a10, a11)), VADD(VADD(a12, a13), VADD(a14, a15))));
  return VSUM(s);
}
