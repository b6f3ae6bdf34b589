// For fuzz targets whose parser reads a file (the scan reader, the image
// decoder: their bounded I/O is part of what is fuzzed): the input written
// to one file per process in /dev/shm (tmpfs: no disk per execution).
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

namespace aprt::fuzz {

inline const char* write_input(const uint8_t* data, size_t size, const char* extension) {
  static std::string path;
  path = "/dev/shm/aprt_fuzz_" + std::to_string(getpid()) + extension;
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return nullptr;
  const bool ok = std::fwrite(data, 1, size, f) == size;
  std::fclose(f);
  return ok ? path.c_str() : nullptr;
}

}  // namespace aprt::fuzz
