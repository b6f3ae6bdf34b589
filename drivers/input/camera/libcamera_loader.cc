// The program's side of the libcamera source: LibcameraSource forwards to the
// source made by aprt_libcamera.so (libcamera_module.h), loaded on first use
// from $APRT_LIBCAMERA_MODULE or ../lib/aprt/ beside the executable (the
// package's /usr/lib/aprt/, the build tree's lib/aprt/). The module stays
// loaded: libcamera's threads run its code until the process ends.
#include "drivers/input/camera/libcamera_module.h"
#include "drivers/module/driver_module.h"

namespace aprt {
namespace {

struct Module {
  const LibcameraModuleApi* api = nullptr;
  Error error;
};

Module load_module() {
  Module m;
  auto entry = open_driver_module("APRT_LIBCAMERA_MODULE", "aprt_libcamera.so",
                                  APRT_LIBCAMERA_MODULE_SYMBOL, "libcamera",
                                  "is aprt installed whole? set APRT_LIBCAMERA_MODULE, or use "
                                  "source type v4l2");
  if (!entry) {
    m.error = entry.error();
    return m;
  }
  const LibcameraModuleApi* api = reinterpret_cast<LibcameraModuleEntry>(entry.value())();
  if (!api || api->abi != LibcameraModuleApi::kAbi) {
    m.error = Error(Errc::kUnsupported,
                    "libcamera: the libcamera module is not this aprt's (another interface "
                    "version); reinstall aprt");
    return m;
  }
  m.api = api;
  return m;
}

const Module& module() {
  static const Module m = load_module();  // once, thread-safe
  return m;
}

}  // namespace

struct LibcameraSource::Impl {
  const LibcameraModuleApi* api = nullptr;
  std::unique_ptr<FrameSource> source;
};

Expected<std::unique_ptr<LibcameraSource>> LibcameraSource::create(const LibcameraOptions& o) {
  const Module& m = module();
  if (!m.api) return m.error;
  auto made = m.api->create(o);
  if (!made) return made.error();
  std::unique_ptr<LibcameraSource> s(new (std::nothrow) LibcameraSource());
  if (!s) return Error(Errc::kOutOfMemory, "libcamera: out of memory");
  s->impl_.reset(new (std::nothrow) Impl{m.api, std::move(made.value())});
  if (!s->impl_) return Error(Errc::kOutOfMemory, "libcamera: out of memory");
  return s;
}

LibcameraSource::~LibcameraSource() = default;

size_t LibcameraSource::max_frame_bytes() const {
  return impl_->source->max_frame_bytes();
}
Status LibcameraSource::start() {
  return impl_->source->start();
}
SourceResult LibcameraSource::next(FrameBuffer* dst, int64_t timeout_ns) {
  return impl_->source->next(dst, timeout_ns);
}
void LibcameraSource::stop() {
  impl_->source->stop();
}
const Error& LibcameraSource::error() const {
  return impl_->source->error();
}
PixelFormat LibcameraSource::format() const {
  return impl_->api->format(*impl_->source);
}
uint64_t LibcameraSource::reopens() const {
  return impl_->api->reopens(*impl_->source);
}
std::string LibcameraSource::list_cameras() {
  const Module& m = module();
  return m.api ? m.api->list_cameras() : std::string(m.error.message());
}

}  // namespace aprt
