// libFuzzer target: any byte string given to the model loader yields a model
// or an error, never a crash, hang or sanitizer report. Checksums are not
// verified here, so that mutations reach the checks behind them; a loaded
// model is also run once (every eval must cope with whatever prepare accepted).
// The same bytes also go through Engine::load_file (from a memfd: the path
// that reads the tables and each weight piece by piece): it must accept and
// refuse exactly what load_memory does, and give the same output.
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "runtime/engine/engine.h"

namespace {

// The bytes as a file (a memfd) and its /proc path; fd -1 on failure.
int as_file(const uint8_t* data, size_t size, char* path, size_t n) {
  const int fd = memfd_create("model_file_fuzz", MFD_CLOEXEC);
  if (fd < 0) return -1;
  if (size > 0 && write(fd, data, size) != static_cast<ssize_t>(size)) {
    close(fd);
    return -1;
  }
  std::snprintf(path, n, "/proc/self/fd/%d", fd);
  return fd;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  aprt::EngineOptions options;
  options.verify_checksums = false;
  options.lock_memory = false;
  auto engine = aprt::Engine::load_memory(data, size, options);
  char path[64];
  const int fd = as_file(data, size, path, sizeof path);
  auto from_file =
      fd >= 0
          ? aprt::Engine::load_file(path, options)
          : aprt::Expected<std::unique_ptr<aprt::Engine>>(aprt::Error(aprt::Errc::kIo, "no memfd"));
  if (fd >= 0) {
    close(fd);
    if (bool(engine) != bool(from_file)) std::abort();  // the two loaders disagree
  }
  if (!engine) {
    (void)engine.error().message();
    return 0;
  }
  aprt::Engine& e = **engine;
  if (e.total_flops() > 200'000'000) return 0;  // keep each input fast
  std::memset(e.input().data, 0, e.input().bytes);
  (void)e.run();
  if (fd >= 0) {
    aprt::Engine& f = **from_file;
    std::memset(f.input().data, 0, f.input().bytes);
    (void)f.run();
    if (std::memcmp(e.output().data, f.output().data, e.output().bytes) != 0) std::abort();
  }
  return 0;
}
