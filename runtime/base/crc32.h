// CRC-32 (IEEE 802.3, reflected, as zlib's crc32): model_bin section checksums.
#pragma once

#include <cstddef>
#include <cstdint>

namespace aprt {

// Continues `crc` (0 to start) over `size` bytes.
uint32_t crc32(const void* data, size_t size, uint32_t crc = 0) noexcept;

}  // namespace aprt
