// File helpers for tests: raw float files, whole-file reads, env lookups.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace aprt::test {

std::vector<uint8_t> read_bytes(const std::string& path);
std::vector<float> read_f32(const std::string& path);
// Directory named by environment variable `var`, or "" (the caller skips).
std::string env_dir(const char* var);
// NCHW [1][c][h][w] -> NHWC.
std::vector<float> nchw_to_nhwc(const std::vector<float>& x, int c, int h, int w);

}  // namespace aprt::test
