// The ISA a kernel written once for every SIMD instruction set is being
// compiled for. kernels/CMakeLists.txt compiles each `*__simd.cc` file once per
// ISA, with that ISA's compiler flags and -DAPRT_SIMD_<ISA>; this header turns
// the definition into the namespace, the vector header, the register tiles and
// the exported names (`dtype_op_tile__isa`):
//
//   APRT_SIMD_NAME(f32_gemm_, APRT_GEMM_TILE)  ->  f32_gemm_8x32__avx512,
//                                                  f32_gemm_6x16__avx2,
//                                                  f32_gemm_8x12__neon
//
// Include it first, at global scope; then open `namespace APRT_SIMD` inside
// aprt::kernels and include APRT_SIMD_VEC, kernels/simd/vmath.inl and the
// family's *_impl.inl there (they are written against the V type and the
// v* functions of the vector header).
#pragma once

#include <cstddef>
#include <cstdint>

#if defined(APRT_SIMD_AVX512)
#include <immintrin.h>
#define APRT_SIMD avx512
#define APRT_SIMD_VEC "kernels/simd/vec_avx512.h"
#define APRT_SIMD_LANES 16
#define APRT_GEMM_TILE 8x32
#define APRT_GEMM_MR 8
#define APRT_GEMM_NV 2  // vectors per GEMM panel: NR = NV * lanes
#define APRT_ATTN_TILE 8x2v
#define APRT_ATTN_ROWS 8  // query rows per attention block (ATTN_TILE's first number)
#define APRT_ATTN_NV 2
#elif defined(APRT_SIMD_AVX2)
#include <immintrin.h>
#define APRT_SIMD avx2
#define APRT_SIMD_VEC "kernels/simd/vec_avx2.h"
#define APRT_SIMD_LANES 8
#define APRT_GEMM_TILE 6x16
#define APRT_GEMM_MR 6
#define APRT_GEMM_NV 2
#define APRT_ATTN_TILE 4x2v
#define APRT_ATTN_ROWS 4
#define APRT_ATTN_NV 2
#elif defined(APRT_SIMD_NEON)
#include <arm_neon.h>
#define APRT_SIMD neon
#define APRT_SIMD_VEC "kernels/simd/vec_neon.h"
#define APRT_SIMD_LANES 4
#define APRT_GEMM_TILE 8x12
#define APRT_GEMM_MR 8
#define APRT_GEMM_NV 3
#define APRT_ATTN_TILE 3x4v
#define APRT_ATTN_ROWS 3
#define APRT_ATTN_NV 4
#else
#error "compile *__simd.cc files through kernels/CMakeLists.txt (-DAPRT_SIMD_<ISA>)"
#endif

#define APRT_SIMD_CAT_(a, b) a##b
#define APRT_SIMD_CAT(a, b) APRT_SIMD_CAT_(a, b)
#define APRT_SIMD_STR_(a) #a
#define APRT_SIMD_STR(a) APRT_SIMD_STR_(a)
// op ## tile ## __ ## isa: an exported kernel of this ISA.
#define APRT_SIMD_NAME(op, tile) \
  APRT_SIMD_CAT(APRT_SIMD_CAT(APRT_SIMD_CAT(op, tile), __), APRT_SIMD)
// The ISA's name as a string: "avx512", "avx2", "neon".
#define APRT_SIMD_ISA_NAME APRT_SIMD_STR(APRT_SIMD)
