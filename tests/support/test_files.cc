#include "tests/support/test_files.h"

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>

namespace aprt::test {

std::vector<uint8_t> read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

std::vector<float> read_f32(const std::string& path) {
  const std::vector<uint8_t> b = read_bytes(path);
  std::vector<float> out(b.size() / 4);
  if (!out.empty()) std::memcpy(out.data(), b.data(), out.size() * 4);
  return out;
}

std::string env_dir(const char* var) {
  const char* v = std::getenv(var);
  return v ? std::string(v) : std::string();
}

std::vector<float> nchw_to_nhwc(const std::vector<float>& x, int c, int h, int w) {
  std::vector<float> y(x.size());
  for (int ch = 0; ch < c; ++ch) {
    for (int i = 0; i < h; ++i) {
      for (int j = 0; j < w; ++j) y[(i * w + j) * c + ch] = x[(ch * h + i) * w + j];
    }
  }
  return y;
}

}  // namespace aprt::test
