// What the CPU (and the OS, for saved vector state) supports, read once.
#pragma once

namespace aprt::kernels {

struct CpuFeatures {
  bool avx2_fma = false;  // AVX2 + FMA3, OS saves YMM state
  bool avx512 = false;    // AVX-512 F/DQ/BW/VL, OS saves ZMM and opmask state
  bool avx512_vnni = false;
  bool avx512_bf16 = false;  // vdpbf16ps / vcvtneps2bf16 (Zen 4, Cooper Lake, Sapphire Rapids)
  bool neon = false;         // aarch64 Advanced SIMD
  bool neon_dot = false;     // SDOT/UDOT (FEAT_DotProd)
};

const CpuFeatures& cpu_features();

// The first instruction-set extension the whole build was compiled to assume
// (a global -march=... in CMAKE_CXX_FLAGS) that this CPU does not report, or
// nullptr. Checked at start so such a binary stops with a message instead of
// dying of SIGILL somewhere in the first frame. The kernels' own ISA flags
// are per-file and chosen at run time; they never show up here.
const char* missing_build_feature();

}  // namespace aprt::kernels
