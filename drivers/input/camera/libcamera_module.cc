// The entry point of aprt_libcamera.so (libcamera_module.h): the libcamera
// source of libcamera_source.cc behind a table of functions. Everything else
// in the module is hidden, so its copy of aprt's base code never meets the
// program's.
#include "drivers/input/camera/libcamera_module.h"

namespace aprt {
namespace {

Expected<std::unique_ptr<FrameSource>> create(const LibcameraOptions& o) {
  auto s = LibcameraSource::create(o);
  if (!s) return s.error();
  return std::unique_ptr<FrameSource>(std::move(s.value()));
}

std::string list_cameras() {
  return LibcameraSource::list_cameras();
}

PixelFormat format(const FrameSource& s) {
  return static_cast<const LibcameraSource&>(s).format();
}

uint64_t reopens(const FrameSource& s) {
  return static_cast<const LibcameraSource&>(s).reopens();
}

}  // namespace
}  // namespace aprt

extern "C" __attribute__((visibility("default"))) const aprt::LibcameraModuleApi*
aprt_libcamera_module() {
  static const aprt::LibcameraModuleApi api{aprt::LibcameraModuleApi::kAbi, aprt::create,
                                            aprt::list_cameras, aprt::format, aprt::reopens};
  return &api;
}
