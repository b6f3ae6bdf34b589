// Loads a model through the installed engine and runs one zero frame:
// proves the headers, the static libraries and their link order are complete.
#include <cstdio>

#include "runtime/engine/engine.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: aprt_consumer MODEL\n");
    return 2;
  }
  auto loaded = aprt::Engine::load_file(argv[1]);
  if (!loaded) {
    std::fprintf(stderr, "aprt_consumer: %s\n", loaded.error().message());
    return 1;
  }
  aprt::Engine& e = *loaded.value();
  if (!e.run()) {
    std::fprintf(stderr, "aprt_consumer: run failed\n");
    return 1;
  }
  std::printf("aprt_consumer: %s ran on %s kernels, output[0] = %g\n", argv[1], e.isa(),
              double(e.output().f32()[0]));
  return 0;
}
