#include "runtime/base/check.h"

#include <atomic>
#include <cstdio>
#include <cstdlib>

namespace aprt {
namespace {

void default_handler(const char* file, int line, const char* message) {
  std::fprintf(stderr, "aprt: fatal: %s (%s:%d)\n", message, file, line);
}

std::atomic<FatalHandler> g_handler{&default_handler};

}  // namespace

FatalHandler set_fatal_handler(FatalHandler handler) noexcept {
  return g_handler.exchange(handler ? handler : &default_handler);
}

void fatal(const char* file, int line, const char* message) noexcept {
  g_handler.load()(file, line, message);
  std::abort();  // a handler that returns still ends the process
}

}  // namespace aprt
