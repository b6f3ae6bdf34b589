// Writes the fuzzer's seed corpus: the small every-op model from the tests.
#include <cstdio>
#include <string>

#include "tests/support/model_builder.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: write_seed DIR\n");
    return 2;
  }
  const auto b = aprt::test::make_small_model();
  const std::string path = std::string(argv[1]) + "/small_model.aprt";
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f || std::fwrite(b.data(), 1, b.size(), f) != b.size()) {
    std::fprintf(stderr, "write_seed: cannot write %s\n", path.c_str());
    return 1;
  }
  std::fclose(f);
  return 0;
}
