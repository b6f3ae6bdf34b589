// The libcamera source lives in a module, aprt_libcamera.so, loaded the first
// time a libcamera camera is asked for (libcamera_loader.cc). libcamera
// brings ~15 libraries with it (GnuTLS, LTTng-UST, libdw, libudev, ...) and
// LTTng-UST starts two listener threads with 8 MiB stacks before main():
// a vehicle with V4L2 cameras or LiDAR pays none of that (docs/configuration.md,
// "Memory"). This is the module's whole interface; the module is built from
// the same sources and compiler as the program, so C++ types cross it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "drivers/input/camera/libcamera_source.h"

namespace aprt {

struct LibcameraModuleApi {
  static constexpr uint32_t kAbi = 1;  // bumped with any change to this struct
  uint32_t abi = kAbi;
  Expected<std::unique_ptr<FrameSource>> (*create)(const LibcameraOptions& o) = nullptr;
  std::string (*list_cameras)() = nullptr;
  PixelFormat (*format)(const FrameSource& source) = nullptr;
  uint64_t (*reopens)(const FrameSource& source) = nullptr;
};

// The module's one exported symbol.
#define APRT_LIBCAMERA_MODULE_SYMBOL "aprt_libcamera_module"
using LibcameraModuleEntry = const LibcameraModuleApi* (*)();

}  // namespace aprt
