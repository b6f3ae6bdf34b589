#include "runtime/cli/load_model.h"

#include <cstdio>

namespace aprt::cli {

std::unique_ptr<Engine> load_image_model(const char* command, const char* path, int threads,
                                         const char* isa) {
  return load_model(command, path, threads, isa, uint32_t(format::Modality::kImage));
}

std::unique_ptr<Engine> load_model(const char* command, const char* path, int threads,
                                   const char* isa, uint32_t modality) {
  EngineOptions opts;
  opts.threads = threads;
  opts.isa = isa;
  opts.expect_modality = modality;
  auto loaded = Engine::load_file(path, opts);
  if (!loaded) {
    std::fprintf(stderr, "aprt %s: %s\n", command, loaded.error().message());
    return nullptr;
  }
  return std::move(loaded.value());
}

}  // namespace aprt::cli
