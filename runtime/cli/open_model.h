// The model of an offline command (eval, infer, inputs), loaded with the
// command's --threads/--isa through the one loader (runtime/loop/model_loader.h);
// on failure the reason is printed as "aprt CMD: ..." and null returned.
#pragma once

#include <cstdint>
#include <memory>

#include "runtime/engine/engine.h"

namespace aprt::cli {

// Any modality (0) or the one given (format::Modality).
std::unique_ptr<Engine> open_model(const char* command, const char* path, int threads,
                                   const char* isa, uint32_t modality = 0);

}  // namespace aprt::cli
