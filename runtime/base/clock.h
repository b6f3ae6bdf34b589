// The loop's clocks: CLOCK_MONOTONIC for ages, deadlines and heartbeats;
// CLOCK_REALTIME only for stamps that leave the process.
#pragma once

#include <cstdint>

namespace aprt {

int64_t monotonic_ns() noexcept;
int64_t realtime_ns() noexcept;

}  // namespace aprt
