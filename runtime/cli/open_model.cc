#include "runtime/cli/open_model.h"

#include <cstdio>
#include <string>

#include "runtime/loop/model_loader.h"

namespace aprt::cli {

std::unique_ptr<Engine> open_model(const char* command, const char* path, int threads,
                                   const char* isa, uint32_t modality) {
  ModelRequest r;
  r.path = path;
  r.engine.threads = threads;
  r.engine.isa = isa;
  r.engine.expect_modality = modality;
  auto loaded = load_model(r, nullptr);
  if (!loaded) {
    std::fprintf(stderr, "aprt %s: %s\n", command, loaded.error().message());
    return nullptr;
  }
  return std::move(loaded.value());
}

}  // namespace aprt::cli
