// Writes the fuzzer's seed corpus: the small every-op model from the tests,
// the same with int8 LINEAR and depthwise ops (so that mutations reach the
// quantisation checks and the int8 ops' prepare), and the small raw-points
// model (the point ops' prepare and kernels, the 'points' metadata).
#include <cstdio>
#include <string>
#include <vector>

#include "tests/support/model_builder.h"

namespace {

bool write(const std::string& path, const std::vector<uint8_t>& b) {
  FILE* f = std::fopen(path.c_str(), "wb");
  const bool ok = f && std::fwrite(b.data(), 1, b.size(), f) == b.size();
  if (f) std::fclose(f);
  if (!ok) std::fprintf(stderr, "write_seed: cannot write %s\n", path.c_str());
  return ok;
}

void int8_dw(aprt::test::ModelBuilder& b) {
  const int op = b.op_index("dw");
  std::vector<int8_t> w(3 * 3 * 8);
  for (size_t i = 0; i < w.size(); ++i) w[i] = int8_t(int((i * 53 + 7) % 255) - 127);
  const int qs = b.constant("dw.w.qscale", {8}, std::vector<float>(8, 0.004f));
  const int wq = b.constant_i8("dw.w.int8", {3, 3, 8}, w, 0.0f, qs);
  b.set_inputs(op, {b.tensor_index("stem.out"), wq, b.tensor_index("dw.b")});
  b.set_param(op, 7, aprt::test::ModelBuilder::f32_bits(0.03f));
  b.set_param(op, 8, 17);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: write_seed DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  const bool ok =
      write(dir + "/small_model.aprt", aprt::test::make_small_model()) &&
      write(dir + "/small_int8_model.aprt", aprt::test::make_small_int8_model(int8_dw)) &&
      write(dir + "/small_points_model.aprt", aprt::test::make_small_points_model());
  return ok ? 0 : 1;
}
