// The libcamera source in a build without libcamera (the aarch64 sysroot, a
// host without libcamera-dev): create() says so; nothing else is reachable.
#include "drivers/input/camera/libcamera_source.h"

namespace aprt {

struct LibcameraSource::Impl {
  Error error;
};

Expected<std::unique_ptr<LibcameraSource>> LibcameraSource::create(const LibcameraOptions&) {
  return Error(Errc::kUnsupported,
               "libcamera: this build of aprt has no libcamera support (install libcamera-dev and "
               "rebuild, or use source type v4l2)");
}
LibcameraSource::~LibcameraSource() = default;
size_t LibcameraSource::max_frame_bytes() const {
  return 0;
}
Status LibcameraSource::start() {
  return impl_->error;
}
SourceResult LibcameraSource::next(FrameBuffer*, int64_t) {
  return SourceResult::kFailed;
}
void LibcameraSource::stop() {}
const Error& LibcameraSource::error() const {
  return impl_->error;
}
PixelFormat LibcameraSource::format() const {
  return PixelFormat::kYuyv;
}
uint64_t LibcameraSource::reopens() const {
  return 0;
}
std::string LibcameraSource::list_cameras() {
  return "(no libcamera support in this build)";
}

}  // namespace aprt
