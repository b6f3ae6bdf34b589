// The image model of an offline command (eval, infer), loaded with the
// command's --threads/--isa; on failure the reason is printed as "aprt CMD: ...".
#pragma once

#include <memory>

#include "runtime/engine/engine.h"

namespace aprt::cli {

std::unique_ptr<Engine> load_image_model(const char* command, const char* path, int threads,
                                         const char* isa);

}  // namespace aprt::cli
