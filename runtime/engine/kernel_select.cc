#include "runtime/engine/kernel_select.h"

#include <cstring>

#include "kernels/common/cpu_features.h"
#include "runtime/common/check.h"

namespace aprt {

Expected<const kernels::KernelSet*> select_kernels(const char* isa) {
  const kernels::CpuFeatures& cpu = kernels::cpu_features();
  struct Candidate {
    const char* name;
    const kernels::KernelSet* set;
    bool runs;
  };
  const Candidate candidates[] = {
      {"avx512", kernels::kernel_set_avx512(), cpu.avx512},
      {"avx2", kernels::kernel_set_avx2(), cpu.avx2_fma},
      {"neon", kernels::kernel_set_neon(), cpu.neon},
  };
  if (!isa || !*isa || std::strcmp(isa, "auto") == 0) {
    for (const Candidate& c : candidates) {
      if (c.set && c.runs) return c.set;
    }
    return static_cast<const kernels::KernelSet*>(nullptr);
  }
  if (std::strcmp(isa, "ref") == 0) return static_cast<const kernels::KernelSet*>(nullptr);
  for (const Candidate& c : candidates) {
    if (std::strcmp(isa, c.name) != 0) continue;
    APRT_ENSURE(c.set != nullptr, Errc::kUnsupported,
                "engine: ISA '%s' is not compiled into this build", isa);
    APRT_ENSURE(c.runs, Errc::kUnsupported,
                "engine: this CPU cannot run the '%s' kernels (forced by APRT_ISA or --isa)", isa);
    return c.set;
  }
  return Error(Errc::kInvalidArgument, "engine: unknown ISA '%s' (auto, ref, avx512, avx2, neon)",
               isa);
}

const kernels::QKernelSet* select_qkernels(const kernels::KernelSet* ks) {
  if (!ks) return nullptr;
  const kernels::CpuFeatures& cpu = kernels::cpu_features();
  const auto pick = [](const kernels::QKernelSet* first, bool runs,
                       const kernels::QKernelSet* second) {
    return first && runs ? first : second;
  };
  if (std::strcmp(ks->isa, "avx512") == 0)
    return pick(kernels::qkernel_set_avx512vnni(), cpu.avx512_vnni, kernels::qkernel_set_avx2());
  if (std::strcmp(ks->isa, "avx2") == 0) return kernels::qkernel_set_avx2();
  if (std::strcmp(ks->isa, "neon") == 0)
    return pick(kernels::qkernel_set_neondot(), cpu.neon_dot, kernels::qkernel_set_neon());
  return nullptr;
}

const kernels::Bf16AttentionKernels* select_bf16_attention(const kernels::KernelSet* ks) {
  if (!ks || std::strcmp(ks->isa, "avx512") != 0 || !kernels::cpu_features().avx512_bf16)
    return nullptr;
  return kernels::bf16_attention_avx512bf16();
}

const char* kernel_set_name(const kernels::KernelSet* ks) {
  return ks ? ks->isa : "ref";
}

}  // namespace aprt
