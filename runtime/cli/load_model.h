// The model of an offline command (eval, infer), loaded with the
// command's --threads/--isa; on failure the reason is printed as "aprt CMD: ...".
#pragma once

#include <memory>

#include "runtime/engine/engine.h"

namespace aprt::cli {

std::unique_ptr<Engine> load_image_model(const char* command, const char* path, int threads,
                                         const char* isa);

// Any modality (0) or the one given.
std::unique_ptr<Engine> load_model(const char* command, const char* path, int threads,
                                   const char* isa, uint32_t modality = 0);

}  // namespace aprt::cli
