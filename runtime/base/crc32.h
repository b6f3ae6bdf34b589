// CRC-32 (IEEE 802.3, reflected, as zlib's crc32): model_bin section checksums.
//
// crc32() runs the fastest implementation this CPU has, chosen once:
// carry-less multiplication folding on x86-64 (PCLMULQDQ; the method of
// Gopal et al., "Fast CRC Computation for Generic Polynomials Using PCLMULQDQ
// Instruction", Intel 2009) or the ARMv8 CRC32 instructions; otherwise the
// slice-by-8 tables. Every model load checks ~the whole file with it, so its
// speed is start-up time: ~1.5 GB/s with tables, >10 GB/s folded.
#pragma once

#include <cstddef>
#include <cstdint>

namespace aprt {

// Continues `crc` (0 to start) over `size` bytes.
uint32_t crc32(const void* data, size_t size, uint32_t crc = 0) noexcept;

// The slice-by-8 reference every other implementation is tested against.
uint32_t crc32__table(const void* data, size_t size, uint32_t crc = 0) noexcept;

// "pclmul", "armv8-crc" or "table": what crc32() runs on this CPU.
const char* crc32_implementation() noexcept;

}  // namespace aprt
