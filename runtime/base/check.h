// Check strengths (see docs/architecture.md, "Errors"):
//   APRT_ENSURE(cond, code, fmt, ...)  load-time validation: returns an Error from
//                                      the enclosing function (which returns
//                                      Status or Expected<T>).
//   APRT_DCHECK(cond)                  debug builds only; for invariants that
//                                      load() has already established.
//   APRT_ENFORCE(cond, msg)            always on; calls the fatal handler, which
//                                      the supervisor maps to FAULT and tests
//                                      can replace.
#pragma once

#include "runtime/base/error.h"

namespace aprt {

using FatalHandler = void (*)(const char* file, int line, const char* message);

// Installs `handler` and returns the previous one. The default prints and aborts.
FatalHandler set_fatal_handler(FatalHandler handler) noexcept;
[[noreturn]] void fatal(const char* file, int line, const char* message) noexcept;

}  // namespace aprt

#define APRT_ENSURE(cond, code, ...)           \
  do {                                         \
    if (!(cond)) {                             \
      return ::aprt::Error(code, __VA_ARGS__); \
    }                                          \
  } while (0)

#define APRT_ENFORCE(cond, message)                          \
  do {                                                       \
    if (!(cond)) ::aprt::fatal(__FILE__, __LINE__, message); \
  } while (0)

#ifdef NDEBUG
#define APRT_DCHECK(cond) \
  do {                    \
  } while (0)
#else
#define APRT_DCHECK(cond) APRT_ENFORCE(cond, "debug check failed: " #cond)
#endif
