// Built with a -march the target CPU may lack (tests/CMakeLists.txt): prints
// what aprt's start-up check says, and exits 70 like `aprt` when it refuses.
#include <cstdio>

#include "kernels/table/cpu_features.h"

int main() {
  if (const char* missing = aprt::kernels::missing_build_feature()) {
    std::printf("refused: this build assumes %s\n", missing);
    return 70;
  }
  std::printf("accepted: the CPU has every feature the build assumes\n");
  return 0;
}
