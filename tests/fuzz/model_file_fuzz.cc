// libFuzzer target: any byte string given to the model loader yields a model
// or an error, never a crash, hang or sanitizer report. Checksums are not
// verified here, so that mutations reach the checks behind them; a loaded
// model is also run once (every eval must cope with whatever prepare accepted).
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "runtime/engine/engine.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  aprt::EngineOptions options;
  options.verify_checksums = false;
  options.lock_memory = false;
  auto engine = aprt::Engine::load_memory(data, size, options);
  if (!engine) {
    (void)engine.error().message();
    return 0;
  }
  aprt::Engine& e = **engine;
  if (e.total_flops() > 200'000'000) return 0;  // keep each input fast
  std::memset(e.input().data, 0, e.input().bytes);
  (void)e.run();
  return 0;
}
