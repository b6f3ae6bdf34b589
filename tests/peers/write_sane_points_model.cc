// Writes the small points model whose estimates pass the sanity checks
// (tests/support/model_builder.h) to a file, for the peer tests' aprt runs.
#include <cstdio>
#include <fstream>

#include "tests/support/model_builder.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: write_sane_points_model OUT.aprt\n");
    return 2;
  }
  const auto bytes = aprt::test::make_sane_small_points_model();
  std::ofstream out(argv[1], std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  if (!out) {
    std::fprintf(stderr, "write_sane_points_model: cannot write %s\n", argv[1]);
    return 1;
  }
  return 0;
}
