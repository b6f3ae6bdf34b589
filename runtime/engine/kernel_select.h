// Chooses the kernel table once, at load, from what the CPU reports.
#pragma once

#include "kernels/common/bf16_attention.h"
#include "kernels/common/kernel_set.h"
#include "kernels/common/qkernel_set.h"
#include "runtime/common/expected.h"

namespace aprt {

// `isa`: null, "" or "auto" picks the best table this CPU runs; "ref" the
// portable reference kernels (returns null); "avx512", "avx2", "neon" force
// one, and fail with a clear message if this build lacks it or this CPU cannot
// run it (never a SIGILL later). The APRT_ISA environment variable is read by
// the engine when EngineOptions::isa is not set.
Expected<const kernels::KernelSet*> select_kernels(const char* isa);

// The int8 kernels that go with the fp32 table `ks`: AVX-512 VNNI with
// "avx512" on a CPU that has VNNI (else the AVX2 int8 kernels), AVX2 with
// "avx2", NEON dotprod with "neon" on a CPU with dotprod (else plain NEON);
// null (the int8 reference) with the reference kernels.
const kernels::QKernelSet* select_qkernels(const kernels::KernelSet* ks);

// The bf16 attention kernels that go with `ks`: AVX-512 BF16 with "avx512"
// on a CPU that has it; null otherwise (the op then rounds Q, K and V to bf16
// for ks's fp32 kernel, or runs the bf16 reference with the reference kernels).
const kernels::Bf16AttentionKernels* select_bf16_attention(const kernels::KernelSet* ks);

// The name of what select_kernels(isa) picks ("ref" for the reference).
const char* kernel_set_name(const kernels::KernelSet* ks);

}  // namespace aprt
