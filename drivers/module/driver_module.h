// Drivers built as modules: a shared object opened the first time its
// driver is asked for and never closed (its objects and the threads of the
// libraries it brings live until the process ends). The program then links
// none of the module's libraries: a vehicle that does not configure the
// driver neither loads nor pays for them (docs/architecture.md, "Modules").
// A module is built from the same sources and compiler as the program, so
// C++ types cross the boundary; each module's table carries an ABI number.
#pragma once

#include "runtime/base/expected.h"

namespace aprt {

// The address of `symbol` in the module file `file`, found at $`env_var`
// when that is set, else as ../lib/aprt/`file` from the running executable
// (the package's /usr/lib/aprt/, the build tree's lib/aprt/). Errors read
// "<what>: cannot load the module PATH: <reason> (<hint>)".
Expected<void*> open_driver_module(const char* env_var, const char* file, const char* symbol,
                                   const char* what, const char* hint);

}  // namespace aprt
