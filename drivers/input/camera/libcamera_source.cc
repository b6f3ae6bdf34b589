#include "drivers/input/camera/libcamera_source.h"

#include <libcamera/camera.h>
#include <libcamera/camera_manager.h>
#include <libcamera/control_ids.h>
#include <libcamera/formats.h>
#include <libcamera/framebuffer.h>
#include <libcamera/framebuffer_allocator.h>
#include <libcamera/request.h>
#include <libcamera/stream.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <vector>

#include "drivers/codec/image_decoder.h"

namespace aprt {
namespace {

struct FormatEntry {
  const char* name;
  libcamera::PixelFormat libcamera;
  PixelFormat aprt;  // what lands in the slot
};

// libcamera's RGB888 / BGR888 are DRM fourccs, named by a little-endian
// 24-bit word: BGR888 is R, G, B in memory (aprt's RGB24), RGB888 is B, G, R.
const FormatEntry kFormats[] = {
    {"YUYV", libcamera::formats::YUYV, PixelFormat::kYuyv},
    {"UYVY", libcamera::formats::UYVY, PixelFormat::kUyvy},
    {"NV12", libcamera::formats::NV12, PixelFormat::kNv12},
    {"RGB24", libcamera::formats::BGR888, PixelFormat::kRgb24},
    {"BGR24", libcamera::formats::RGB888, PixelFormat::kBgr24},
    {"MJPEG", libcamera::formats::MJPEG, PixelFormat::kRgb24},
};

// libcamera allows one CameraManager per process; every source shares it.
std::shared_ptr<libcamera::CameraManager> shared_manager(Error* err) {
  static std::mutex m;
  static std::weak_ptr<libcamera::CameraManager> weak;
  std::lock_guard<std::mutex> lock(m);
  if (auto cm = weak.lock()) return cm;
  // libcamera logs every camera it probes at INFO; aprt keeps its log for its
  // own messages unless the user asks libcamera for more. (Its categories are
  // created on first use and take their level from this variable, read when
  // libcamera's logger starts: before the manager exists.)
  setenv("LIBCAMERA_LOG_LEVELS", "*:WARN", 0);
  auto cm = std::make_shared<libcamera::CameraManager>();
  if (const int r = cm->start(); r != 0) {
    *err = Error(Errc::kIo, "libcamera: the camera manager did not start: %s", std::strerror(-r));
    return nullptr;
  }
  weak = cm;
  return cm;
}

std::string camera_list_text(libcamera::CameraManager& cm) {
  std::string s;
  const auto cams = cm.cameras();
  for (size_t i = 0; i < cams.size(); ++i) {
    s += (s.empty() ? "" : ", ") + std::to_string(i) + ": '" + cams[i]->id() + "'";
  }
  return s.empty() ? "none" : s;
}

// A camera that stopped delivering while streaming -- unplugged without
// libcamera hearing of it (no hotplug event: no udevd, or a device that hung)
// -- is not stopped: libcamera 0.0.3 then waits for requests a dead device
// never returns and aborts on the assertion that none are pending
// (PipelineHandler::stop()). Such a camera, its buffers and requests are set
// aside here for the rest of the process instead; never freed (freeing them
// calls into the dead pipeline too). A few per unplug: bounded by the unplugs.
struct Abandoned {
  std::shared_ptr<libcamera::CameraManager> cm;
  std::shared_ptr<libcamera::Camera> camera;
  std::unique_ptr<libcamera::CameraConfiguration> config;
  std::unique_ptr<libcamera::FrameBufferAllocator> allocator;
  std::vector<std::unique_ptr<libcamera::Request>> requests;
};
std::vector<Abandoned*>& abandoned() {
  static auto* list = new std::vector<Abandoned*>();  // never destroyed: see above
  return *list;
}

}  // namespace

struct LibcameraSource::Impl {
  LibcameraOptions o;
  const FormatEntry* fmt = nullptr;
  std::unique_ptr<ImageDecoder> decoder;  // MJPEG only
  std::shared_ptr<libcamera::CameraManager> cm;
  std::shared_ptr<libcamera::Camera> camera;
  std::unique_ptr<libcamera::CameraConfiguration> config;
  libcamera::Stream* stream = nullptr;
  std::unique_ptr<libcamera::FrameBufferAllocator> allocator;
  std::vector<std::unique_ptr<libcamera::Request>> requests;
  struct Map {
    void* addr = MAP_FAILED;
    size_t length = 0;
  };
  std::vector<Map> maps;
  // Per buffer (its cookie), per plane: the mapped bytes.
  struct PlaneView {
    const uint8_t* data = nullptr;
    size_t length = 0;
  };
  std::vector<std::vector<PlaneView>> planes;
  bool acquired = false, started = false, streaming = false;
  // Requests carry the generation of the opening they belong to (the
  // cookie's high half): a late completion from an abandoned camera is ignored.
  std::atomic<uint32_t> generation{0};
  std::atomic<int64_t> last_complete_ns{0};  // libcamera's thread -> the capture thread
  int64_t opened_ns = 0;
  int64_t stall_ns = 2000000000;  // nothing for this long while streaming: gone
  int event_fd = -1;
  // Completed requests, libcamera's thread -> the capture thread (SPSC).
  static constexpr uint32_t kRing = 64;
  libcamera::Request* ring[kRing] = {};
  std::atomic<uint32_t> head{0}, tail{0};
  std::atomic<bool> gone{false};
  int width = 0, height = 0;
  size_t stride = 0, frame_bytes = 0, max_bytes = 0;
  int64_t retry_at_ns = 0, retry_delay_ns = 0;
  uint64_t reopens = 0;
  Error error;

  void wake() {
    const uint64_t one = 1;
    (void)!write(event_fd, &one, sizeof one);
  }
  // libcamera's thread: no allocation, no lock, no wait.
  void on_complete(libcamera::Request* r) {
    if (r->status() == libcamera::Request::RequestCancelled) return;
    if (uint32_t(r->cookie() >> 32) != generation.load(std::memory_order_acquire)) return;
    last_complete_ns.store(monotonic_ns(), std::memory_order_release);
    const uint32_t h = head.load(std::memory_order_relaxed);
    if (h - tail.load(std::memory_order_acquire) >= kRing)
      return;  // cannot happen: kRing > buffers
    ring[h % kRing] = r;
    head.store(h + 1, std::memory_order_release);
    wake();
  }
  void on_disconnect() {
    gone.store(true, std::memory_order_release);
    wake();
  }

  Status open();
  void close(bool vanished = false);
  Status fail(Errc code, const char* fmt_text, const std::string& a, const std::string& b = "") {
    error = Error(code, fmt_text, a.c_str(), b.c_str());
    return error;
  }
};

Expected<std::unique_ptr<LibcameraSource>> LibcameraSource::create(const LibcameraOptions& o) {
  std::unique_ptr<LibcameraSource> s(new (std::nothrow) LibcameraSource());
  if (!s) return Error(Errc::kOutOfMemory, "libcamera: out of memory");
  s->impl_.reset(new (std::nothrow) Impl());
  if (!s->impl_) return Error(Errc::kOutOfMemory, "libcamera: out of memory");
  Impl& m = *s->impl_;
  m.o = o;
  for (const FormatEntry& f : kFormats) {
    if (o.format == f.name) m.fmt = &f;
  }
  if (!m.fmt) {
    return Error(Errc::kInvalidArgument,
                 "libcamera: pixel format '%s' is not supported (YUYV, UYVY, NV12, RGB24, BGR24, "
                 "MJPEG)",
                 o.format.c_str());
  }
  if (o.role != "viewfinder" && o.role != "video" && o.role != "still") {
    return Error(Errc::kInvalidArgument,
                 "libcamera: stream role '%s' is not one of viewfinder, video, still",
                 o.role.c_str());
  }
  if (o.width < 16 || o.height < 16 || o.width > 8192 || o.height > 8192 || o.buffers < 2 ||
      o.buffers > 32 || o.fps < 1 || o.fps > 1000) {
    return Error(Errc::kInvalidArgument,
                 "libcamera: %dx%d at %d fps with %d buffers is out of range", o.width, o.height,
                 o.fps, o.buffers);
  }
  const PixelFormat pf = m.fmt->aprt;
  // Room for a driver's padded stride (up to 64-byte alignment of each row).
  const size_t stride = (min_stride(pf, o.width) + 63) / 64 * 64;
  m.max_bytes = pf == PixelFormat::kNv12 ? stride * size_t(o.height) * 3 / 2 + stride
                                         : stride * size_t(o.height);
  if (o.format == "MJPEG") {
    auto d = ImageDecoder::create(size_t(o.width) * o.height * 3);
    if (!d) return d.error();
    m.decoder = std::move(d.value());
    m.max_bytes = frame_bytes(PixelFormat::kRgb24, o.width, o.height);
  }
  m.event_fd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (m.event_fd < 0) {
    return Error(Errc::kIo, "libcamera: eventfd: %s", std::strerror(errno));
  }
  m.retry_delay_ns = o.retry_ns;
  m.stall_ns = std::max<int64_t>(2000000000, 5000000000LL / o.fps);  // 2 s, or 5 frames
  Error err;
  m.cm = shared_manager(&err);
  if (!m.cm) return err;
  return s;
}

LibcameraSource::~LibcameraSource() {
  if (!impl_) return;
  impl_->close();
  if (impl_->event_fd >= 0) ::close(impl_->event_fd);
}

size_t LibcameraSource::max_frame_bytes() const {
  return impl_->max_bytes;
}
const Error& LibcameraSource::error() const {
  return impl_->error;
}
PixelFormat LibcameraSource::format() const {
  return impl_->fmt->aprt;
}
uint64_t LibcameraSource::reopens() const {
  return impl_->reopens;
}

std::string LibcameraSource::list_cameras() {
  Error err;
  auto cm = shared_manager(&err);
  if (!cm) return err.message();
  return camera_list_text(*cm);
}

Status LibcameraSource::Impl::open() {
  // The camera: by id, by index, or the first.
  const auto cams = cm->cameras();
  char* end = nullptr;
  const long index = o.camera.empty() ? 0 : std::strtol(o.camera.c_str(), &end, 10);
  const bool by_index = o.camera.empty() || (end && !*end);
  if (by_index) {
    if (index < 0 || size_t(index) >= cams.size()) {
      return fail(Errc::kNotFound, "libcamera: no camera %s (cameras: %s)",
                  o.camera.empty() ? std::string("at all") : "number " + o.camera,
                  camera_list_text(*cm));
    }
    camera = cams[size_t(index)];
  } else {
    camera = cm->get(o.camera);
    if (!camera) {
      return fail(Errc::kNotFound, "libcamera: no camera '%s' (cameras: %s)", o.camera,
                  camera_list_text(*cm));
    }
  }
  for (const Abandoned* a : abandoned()) {
    if (a->camera == camera) {
      const std::string id = camera->id();
      camera.reset();
      return fail(Errc::kNotFound,
                  "libcamera: camera '%s' has not come back (the one that stopped delivering is "
                  "set aside; libcamera has announced no new one)",
                  id);
    }
  }
  if (camera->acquire() != 0) {
    return fail(Errc::kIo, "libcamera: camera '%s' is in use (by another process?)", camera->id());
  }
  acquired = true;
  const libcamera::StreamRole role = o.role == "video"   ? libcamera::StreamRole::VideoRecording
                                     : o.role == "still" ? libcamera::StreamRole::StillCapture
                                                         : libcamera::StreamRole::Viewfinder;
  config = camera->generateConfiguration({role});
  if (!config || config->size() != 1) {
    return fail(Errc::kUnsupported, "libcamera: camera '%s' has no %s stream", camera->id(),
                o.role);
  }
  libcamera::StreamConfiguration& sc = config->at(0);
  sc.pixelFormat = fmt->libcamera;
  sc.size = libcamera::Size(unsigned(o.width), unsigned(o.height));
  sc.bufferCount = unsigned(o.buffers);
  const auto status = config->validate();
  if (status == libcamera::CameraConfiguration::Invalid || sc.pixelFormat != fmt->libcamera ||
      sc.size.width != unsigned(o.width) || sc.size.height != unsigned(o.height)) {
    std::string offers;
    for (const libcamera::PixelFormat& p : sc.formats().pixelformats()) {
      offers += (offers.empty() ? "" : ", ") + p.toString();
    }
    char what[160];
    std::snprintf(what, sizeof what, "%s at %dx%d (it would give %s %ux%u; it offers %s)",
                  o.format.c_str(), o.width, o.height, sc.pixelFormat.toString().c_str(),
                  sc.size.width, sc.size.height, offers.empty() ? "nothing" : offers.c_str());
    return fail(Errc::kUnsupported, "libcamera: camera '%s' cannot deliver %s", camera->id(), what);
  }
  if (camera->configure(config.get()) != 0) {
    return fail(Errc::kIo, "libcamera: camera '%s' refused the configuration %s", camera->id(),
                sc.toString());
  }
  stream = sc.stream();
  width = int(sc.size.width);
  height = int(sc.size.height);
  stride = decoder ? min_stride(PixelFormat::kRgb24, width)
                   : (sc.stride ? size_t(sc.stride) : min_stride(fmt->aprt, width));
  frame_bytes =
      fmt->aprt == PixelFormat::kNv12 ? stride * size_t(height) * 3 / 2 : stride * size_t(height);
  if (!decoder && frame_bytes > max_bytes) {
    return fail(Errc::kUnsupported,
                "libcamera: camera '%s' pads rows to %s bytes, more than aprt sized for",
                camera->id(), std::to_string(stride));
  }
  allocator = std::make_unique<libcamera::FrameBufferAllocator>(camera);
  if (allocator->allocate(stream) < 0) {
    return fail(Errc::kOutOfMemory, "libcamera: camera '%s': cannot allocate %s buffers",
                camera->id(), std::to_string(o.buffers));
  }
  const auto& buffers = allocator->buffers(stream);
  planes.assign(buffers.size(), {});
  for (size_t i = 0; i < buffers.size(); ++i) {
    for (const libcamera::FrameBuffer::Plane& p : buffers[i]->planes()) {
      // Planes of one buffer often share a dmabuf at different offsets: map
      // each plane's range on its own (simple, and buffers are few).
      const size_t len = size_t(p.offset) + p.length;
      void* addr = mmap(nullptr, len, PROT_READ, MAP_SHARED, p.fd.get(), 0);
      if (addr == MAP_FAILED) {
        return fail(Errc::kIo, "libcamera: camera '%s': cannot map a buffer: %s", camera->id(),
                    std::strerror(errno));
      }
      maps.push_back({addr, len});
      planes[i].push_back({static_cast<const uint8_t*>(addr) + p.offset, p.length});
    }
    std::unique_ptr<libcamera::Request> r =
        camera->createRequest((uint64_t(generation.load()) << 32) | i);
    if (!r || r->addBuffer(stream, buffers[i].get()) != 0) {
      return fail(Errc::kIo, "libcamera: camera '%s': cannot create a request", camera->id());
    }
    requests.push_back(std::move(r));
  }
  gone.store(false);
  camera->requestCompleted.connect(this, &Impl::on_complete);
  camera->disconnected.connect(this, &Impl::on_disconnect);
  libcamera::ControlList controls(camera->controls());
  if (camera->controls().count(&libcamera::controls::FrameDurationLimits)) {
    const int64_t us = 1000000 / o.fps;
    controls.set(libcamera::controls::FrameDurationLimits,
                 libcamera::Span<const int64_t, 2>({us, us}));
  }
  if (camera->start(&controls) != 0) {
    return fail(Errc::kIo, "libcamera: camera '%s' did not start streaming", camera->id());
  }
  started = true;
  opened_ns = monotonic_ns();
  last_complete_ns.store(0, std::memory_order_release);
  for (auto& r : requests) {
    if (camera->queueRequest(r.get()) != 0) {
      return fail(Errc::kIo, "libcamera: camera '%s' refused a request", camera->id());
    }
  }
  streaming = true;
  return ok();
}

void LibcameraSource::Impl::close(bool vanished) {
  generation.fetch_add(1, std::memory_order_acq_rel);  // what is still queued is not ours now
  if (camera && vanished && started) {
    camera->requestCompleted.disconnect(this);
    camera->disconnected.disconnect(this);
    for (Map& m : maps) munmap(m.addr, m.length);
    maps.clear();
    planes.clear();
    auto* a = new (std::nothrow) Abandoned{cm, std::move(camera), std::move(config),
                                           std::move(allocator), std::move(requests)};
    if (a) abandoned().push_back(a);  // out of memory: leaked all the same, never stopped
    camera.reset();
    acquired = started = streaming = false;
    requests.clear();
    head.store(0);
    tail.store(0);
    uint64_t drain;
    while (event_fd >= 0 && read(event_fd, &drain, sizeof drain) > 0) {
    }
    return;
  }
  if (camera) {
    if (started) camera->stop();  // completes what is queued as cancelled
    camera->requestCompleted.disconnect(this);
    camera->disconnected.disconnect(this);
  }
  started = streaming = false;
  requests.clear();
  for (Map& m : maps) munmap(m.addr, m.length);
  maps.clear();
  planes.clear();
  allocator.reset();
  config.reset();
  if (camera && acquired) camera->release();
  acquired = false;
  camera.reset();
  head.store(0);
  tail.store(0);
  uint64_t drain;
  while (event_fd >= 0 && read(event_fd, &drain, sizeof drain) > 0) {
  }
}

Status LibcameraSource::start() {
  Impl& m = *impl_;
  Status s = m.open();
  if (!s) {
    m.close();
    m.retry_at_ns = monotonic_ns() + m.retry_delay_ns;
  }
  return s;
}

void LibcameraSource::stop() {
  impl_->close();
}

SourceResult LibcameraSource::next(FrameBuffer* dst, int64_t timeout_ns) {
  Impl& m = *impl_;
  if (!m.streaming) {
    // Reopen with back-off; until then the capture thread keeps beating.
    const int64_t now = monotonic_ns();
    if (now < m.retry_at_ns) {
      const int64_t wait = m.retry_at_ns - now < timeout_ns ? m.retry_at_ns - now : timeout_ns;
      const timespec ts{time_t(wait / 1000000000), long(wait % 1000000000)};
      nanosleep(&ts, nullptr);
      return SourceResult::kTimeout;
    }
    Status s = m.open();
    if (!s) {
      m.close();
      m.retry_at_ns = now + m.retry_delay_ns;
      if (m.retry_delay_ns < 8 * m.o.retry_ns) m.retry_delay_ns *= 2;
      return SourceResult::kFailed;
    }
    ++m.reopens;
    m.retry_delay_ns = m.o.retry_ns;
  }
  const int64_t last = std::max(m.last_complete_ns.load(std::memory_order_acquire), m.opened_ns);
  if (!m.gone.load(std::memory_order_acquire) && monotonic_ns() - last > m.stall_ns) {
    m.error = Error(Errc::kIo,
                    "libcamera: camera '%s' delivered nothing for %.1f s (unplugged without a "
                    "hotplug event, or hung): set aside, reopening with back-off",
                    m.camera ? m.camera->id().c_str() : m.o.camera.c_str(),
                    double(monotonic_ns() - last) * 1e-9);
    m.close(/*vanished=*/true);
    m.retry_at_ns = monotonic_ns() + m.retry_delay_ns;
    return SourceResult::kFailed;
  }
  if (m.tail.load(std::memory_order_relaxed) == m.head.load(std::memory_order_acquire) &&
      !m.gone.load(std::memory_order_acquire)) {
    pollfd p{m.event_fd, POLLIN, 0};
    const int r = poll(&p, 1, int(timeout_ns / 1000000));
    if (r <= 0) return SourceResult::kTimeout;
    uint64_t n;
    (void)!read(m.event_fd, &n, sizeof n);
  }
  if (m.gone.load(std::memory_order_acquire)) {
    m.error =
        Error(Errc::kIo, "libcamera: camera '%s' disconnected: closed, reopening with back-off",
              m.camera ? m.camera->id().c_str() : m.o.camera.c_str());
    m.close();
    m.retry_at_ns = monotonic_ns() + m.retry_delay_ns;
    return SourceResult::kFailed;
  }
  const uint32_t t = m.tail.load(std::memory_order_relaxed);
  if (t == m.head.load(std::memory_order_acquire)) return SourceResult::kTimeout;
  libcamera::Request* req = m.ring[t % Impl::kRing];
  m.tail.store(t + 1, std::memory_order_release);

  SourceResult result = SourceResult::kFrame;
  const auto it = req->buffers().find(m.stream);
  libcamera::FrameBuffer* fb = it == req->buffers().end() ? nullptr : it->second;
  const size_t cookie =
      size_t(req->cookie() & 0xffffffffu);  // the buffer; above it, the generation
  if (!fb || cookie >= m.planes.size()) {
    m.error = Error(Errc::kIo, "libcamera: a request came back without its buffer");
    result = SourceResult::kSkipped;
  } else if (fb->metadata().status != libcamera::FrameMetadata::FrameSuccess) {
    m.error = Error(
        Errc::kIo, "libcamera: camera '%s' marked frame %u %s", m.camera->id().c_str(),
        fb->metadata().sequence,
        fb->metadata().status == libcamera::FrameMetadata::FrameError ? "corrupt" : "cancelled");
    result = SourceResult::kSkipped;
  } else {
    const auto& md = fb->metadata();
    const auto& views = m.planes[cookie];
    const auto mdp = md.planes();
    if (m.decoder) {
      char what[96];
      std::snprintf(what, sizeof what, "libcamera frame %u (MJPEG)", md.sequence);
      const size_t used = mdp.size() ? mdp[0].bytesused : 0;
      auto img =
          used <= views[0].length
              ? m.decoder->decode_jpeg_memory(views[0].data, used, dst->data, dst->capacity, what)
              : Expected<DecodedImage>(Error(Errc::kTruncated, "libcamera: %s: bad size", what));
      if (!img) {
        m.error = img.error();
        result = SourceResult::kSkipped;
      } else if (img->width != m.width || img->height != m.height) {
        m.error = Error(Errc::kInvalidArgument, "libcamera: %s is %dx%d, the stream %dx%d", what,
                        img->width, img->height, m.width, m.height);
        result = SourceResult::kSkipped;
      }
    } else {
      // Planes one after another: for NV12, Y (stride x height) then UV,
      // which is aprt's NV12 layout.
      size_t off = 0, used_total = 0;
      for (size_t p = 0; p < views.size() && p < mdp.size(); ++p) {
        const size_t used = mdp[p].bytesused < views[p].length ? mdp[p].bytesused : views[p].length;
        const size_t n = off + used > dst->capacity ? dst->capacity - off : used;
        std::memcpy(dst->data + off, views[p].data, n);
        off += n;
        used_total += mdp[p].bytesused;
      }
      if (used_total < m.frame_bytes) {
        m.error = Error(Errc::kTruncated, "libcamera: frame %u truncated (%zu of %zu bytes)",
                        md.sequence, used_total, m.frame_bytes);
        result = SourceResult::kSkipped;
      }
    }
    if (result == SourceResult::kFrame) {
      FrameInfo& info = dst->info;
      info.sequence = md.sequence;
      info.capture_ns = int64_t(md.timestamp);
      info.width = m.width;
      info.height = m.height;
      info.format = m.fmt->aprt;
      info.stride = m.stride;
      info.bytes = m.decoder ? m.stride * size_t(m.height) : m.frame_bytes;
      info.has_truth = false;
      std::snprintf(info.name, sizeof info.name, "libcamera:%u", md.sequence);
    }
  }
  req->reuse(libcamera::Request::ReuseBuffers);
  if (m.camera->queueRequest(req) != 0) {
    m.error = Error(Errc::kIo, "libcamera: camera '%s' refused a request again: closed, reopening",
                    m.camera->id().c_str());
    m.close();
    m.retry_at_ns = monotonic_ns() + m.retry_delay_ns;
    return SourceResult::kFailed;
  }
  return result;
}

}  // namespace aprt
