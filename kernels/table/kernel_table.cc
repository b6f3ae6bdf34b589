// The one kernel picker and the list of which table parts go together.
// Compiled for the baseline ISA: it only takes addresses; every kernel lives
// in its own ISA-flagged translation unit.
#include "kernels/table/kernel_table.h"

#include <cstring>

#include "runtime/base/check.h"

namespace aprt::kernels {

#if defined(__x86_64__) && defined(APRT_KERNELS_X86)
extern const KernelSet f32_kernels__avx512, f32_kernels__avx2;
extern const QKernelSet qs8_kernels__avx512vnni, qs8_kernels__avx2;
extern const Bf16AttentionKernels bf16_attention_kernels__avx512bf16;
#elif defined(__aarch64__) && defined(APRT_KERNELS_ARM)
extern const KernelSet f32_kernels__neon;
extern const QKernelSet qs8_kernels__neondot, qs8_kernels__neon;
#endif

std::span<const IsaParts> isa_parts() {
  static const CpuFeatures& c = cpu_features();
  static const IsaParts parts[] = {
#if defined(__x86_64__) && defined(APRT_KERNELS_X86)
    {.isa = "avx512",
     .f32 = &f32_kernels__avx512,
     .f32_runs = c.avx512,
     .qs8 = {&qs8_kernels__avx512vnni, &qs8_kernels__avx2},
     .qs8_runs = {c.avx512_vnni, c.avx2_fma},
     .bf16 = &bf16_attention_kernels__avx512bf16,
     .bf16_runs = c.avx512_bf16},
    {.isa = "avx2",
     .f32 = &f32_kernels__avx2,
     .f32_runs = c.avx2_fma,
     .qs8 = {&qs8_kernels__avx2, nullptr},
     .qs8_runs = {c.avx2_fma, false},
     .bf16 = nullptr,
     .bf16_runs = false},
#elif defined(__aarch64__) && defined(APRT_KERNELS_ARM)
    {.isa = "neon",
     .f32 = &f32_kernels__neon,
     .f32_runs = c.neon,
     .qs8 = {&qs8_kernels__neondot, &qs8_kernels__neon},
     .qs8_runs = {c.neon_dot, c.neon},
     .bf16 = nullptr,
     .bf16_runs = false},
#endif
    // A build for another target has no fast kernels: the reference only.
    {.isa = nullptr,
     .f32 = nullptr,
     .f32_runs = false,
     .qs8 = {},
     .qs8_runs = {},
     .bf16 = nullptr,
     .bf16_runs = false},
  };
  return {parts, sizeof parts / sizeof parts[0] - 1};
}

namespace {

KernelTable table_of(const IsaParts& p) {
  KernelTable t;
  t.f32 = p.f32;
  for (int i = 0; i < 2; ++i) {
    if (p.qs8[i] && p.qs8_runs[i]) {
      t.qs8 = p.qs8[i];
      break;
    }
  }
  if (p.bf16 && p.bf16_runs) t.bf16 = p.bf16;
  return t;
}

}  // namespace

Expected<KernelTable> pick_kernels(const char* isa) {
  const std::span<const IsaParts> parts = isa_parts();
  if (!isa || !*isa || std::strcmp(isa, "auto") == 0) {
    for (const IsaParts& p : parts) {
      if (p.f32_runs) return table_of(p);
    }
    return KernelTable{};
  }
  if (std::strcmp(isa, "ref") == 0) return KernelTable{};
  for (const IsaParts& p : parts) {
    if (std::strcmp(isa, p.isa) != 0) continue;
    APRT_ENSURE(p.f32_runs, Errc::kIsaUnavailable,
                "engine: this CPU cannot run the '%s' kernels (forced by APRT_ISA or --isa)", isa);
    return table_of(p);
  }
  for (const char* known : {"avx512", "avx2", "neon"}) {
    APRT_ENSURE(std::strcmp(isa, known) != 0, Errc::kIsaUnavailable,
                "engine: ISA '%s' is not compiled into this build", isa);
  }
  return Error(Errc::kInvalidArgument, "engine: unknown ISA '%s' (auto, ref, avx512, avx2, neon)",
               isa);
}

}  // namespace aprt::kernels
