// What the CPU (and the OS, for saved vector state) supports, read once.
#pragma once

namespace aprt::kernels {

struct CpuFeatures {
  bool avx2_fma = false;  // AVX2 + FMA3, OS saves YMM state
  bool avx512 = false;    // AVX-512 F/DQ/BW/VL, OS saves ZMM and opmask state
  bool avx512_vnni = false;
  bool neon = false;      // aarch64 Advanced SIMD
  bool neon_dot = false;  // SDOT/UDOT (FEAT_DotProd)
};

const CpuFeatures& cpu_features();

}  // namespace aprt::kernels
