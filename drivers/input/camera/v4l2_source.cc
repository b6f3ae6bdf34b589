#include "drivers/input/camera/v4l2_source.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <new>

#include "drivers/codec/image_decoder.h"
#include "drivers/input/camera/v4l2_devices.h"

namespace aprt {
namespace {

struct FormatName {
  const char* name;
  uint32_t fourcc;
  PixelFormat format;
};

constexpr FormatName kFormats[] = {
    {"YUYV", V4L2_PIX_FMT_YUYV, PixelFormat::kYuyv},
    {"UYVY", V4L2_PIX_FMT_UYVY, PixelFormat::kUyvy},
    {"NV12", V4L2_PIX_FMT_NV12, PixelFormat::kNv12},
    {"RGB24", V4L2_PIX_FMT_RGB24, PixelFormat::kRgb24},
    {"BGR24", V4L2_PIX_FMT_BGR24, PixelFormat::kBgr24},
    // Decoded on the capture thread into the slot as RGB24 (libjpeg-turbo).
    {"MJPEG", V4L2_PIX_FMT_MJPEG, PixelFormat::kRgb24},
};

// ioctl, retried on EINTR.
int xioctl(int fd, unsigned long request, void* arg) {
  int r;
  do {
    r = ioctl(fd, request, arg);
  } while (r < 0 && errno == EINTR);
  return r;
}

void fourcc_text(uint32_t f, char out[5]) {
  for (int i = 0; i < 4; ++i) out[i] = char((f >> (8 * i)) & 0xFF);
  out[4] = '\0';
}

}  // namespace

Expected<std::unique_ptr<V4l2Source>> V4l2Source::create(const V4l2Options& o) {
  std::unique_ptr<V4l2Source> s(new (std::nothrow) V4l2Source());
  if (!s) return Error(Errc::kOutOfMemory, "v4l2: out of memory");
  s->o_ = o;
  bool known = false;
  for (const auto& f : kFormats) {
    if (o.format == f.name) {
      s->fourcc_ = f.fourcc;
      s->format_ = f.format;
      known = true;
    }
  }
  if (!known) {
    return Error(Errc::kUnsupported,
                 "v4l2: pixel format '%s' is not supported (YUYV, UYVY, NV12, RGB24, BGR24, MJPEG)",
                 o.format.c_str());
  }
  if (o.buffers < 2 || o.buffers > kMaxBuffers) {
    return Error(Errc::kInvalidArgument, "v4l2: buffers %d outside [2, %d]", o.buffers,
                 kMaxBuffers);
  }
  // The slot is sized for the configured frame; a device that insists on a
  // larger one is refused at start() (the slot cannot grow after start-up).
  s->max_bytes_ = frame_bytes(s->format_, o.width, o.height) + 4096;
  if (s->fourcc_ == V4L2_PIX_FMT_MJPEG) {
    // No file buffer and no PNG arena: only the JPEG decompressor is used.
    auto d = ImageDecoder::create(1, 4096);
    if (!d) return d.error();
    s->decoder_ = std::move(d.value());
  }
  s->retry_delay_ns_ = o.retry_ns;
  return s;
}

V4l2Source::~V4l2Source() {
  close_device();
}

void V4l2Source::close_device() {
  if (fd_ >= 0 && streaming_) {
    v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    xioctl(fd_, VIDIOC_STREAMOFF, &type);
  }
  streaming_ = false;
  for (int i = 0; i < mapped_; ++i) munmap(maps_[i], lengths_[i]);
  mapped_ = 0;
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
}

void V4l2Source::fill_info(FrameBuffer* dst, const v4l2_buffer& b, size_t bytes) {
  FrameInfo& f = dst->info;
  f = FrameInfo{};
  f.sequence = sequence_++;
  f.capture_ns = int64_t(b.timestamp.tv_sec) * 1000000000 + int64_t(b.timestamp.tv_usec) * 1000;
  if (!(b.flags & V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) || f.capture_ns == 0) {
    f.capture_ns = monotonic_ns();
  }
  f.width = width_;
  f.height = height_;
  f.format = format_;
  f.stride = stride_;
  f.bytes = bytes;
  std::snprintf(f.name, sizeof f.name, "%s#%u", o_.device.c_str(), b.sequence);
}

Status V4l2Source::open_device() {
  // By path, or looked up by card name / bus_info on every (re)open: a camera
  // that comes back may have another node number.
  char dev[256];
  if (Status s = resolve_v4l2_device(o_.device.c_str(), dev, sizeof dev); !s) return s;
  fd_ = open(dev, O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    const int e = errno;
    return Error(e == ENOENT ? Errc::kNotFound : Errc::kIo,
                 "v4l2: cannot open %s: %s (is the camera connected and its driver loaded?)", dev,
                 std::strerror(e));
  }
  v4l2_capability cap{};
  if (xioctl(fd_, VIDIOC_QUERYCAP, &cap) != 0) {
    return Error(Errc::kUnsupported, "v4l2: %s is not a V4L2 device (%s)", dev,
                 std::strerror(errno));
  }
  const uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE) || !(caps & V4L2_CAP_STREAMING)) {
    return Error(Errc::kUnsupported,
                 "v4l2: %s (%s) is not a streaming video capture device (capabilities 0x%08x)", dev,
                 reinterpret_cast<const char*>(cap.card), caps);
  }
  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = uint32_t(o_.width);
  fmt.fmt.pix.height = uint32_t(o_.height);
  fmt.fmt.pix.pixelformat = fourcc_;
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  if (xioctl(fd_, VIDIOC_S_FMT, &fmt) != 0 || fmt.fmt.pix.pixelformat != fourcc_) {
    char offered[160] = "";
    v4l2_fmtdesc d{};
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    for (d.index = 0; xioctl(fd_, VIDIOC_ENUM_FMT, &d) == 0 && d.index < 16; ++d.index) {
      char t[5];
      fourcc_text(d.pixelformat, t);
      std::strncat(offered, offered[0] ? " " : "", sizeof offered - std::strlen(offered) - 1);
      std::strncat(offered, t, sizeof offered - std::strlen(offered) - 1);
    }
    return Error(Errc::kUnsupported, "v4l2: %s does not deliver %s (it offers: %s)", dev,
                 o_.format.c_str(), offered[0] ? offered : "nothing");
  }
  width_ = int(fmt.fmt.pix.width);
  height_ = int(fmt.fmt.pix.height);
  stride_ = fmt.fmt.pix.bytesperline ? fmt.fmt.pix.bytesperline : min_stride(format_, width_);
  if (decoder_) stride_ = min_stride(format_, width_);  // the decoded RGB rows
  const size_t need =
      format_ == PixelFormat::kNv12 ? stride_ * size_t(height_) * 3 / 2 : stride_ * size_t(height_);
  if (need > max_bytes_) {
    return Error(Errc::kInvalidArgument,
                 "v4l2: %s negotiated %dx%d (%zu bytes a frame), larger than the configured %dx%d: "
                 "configure source.v4l2.width/height to what the camera delivers",
                 dev, width_, height_, need, o_.width, o_.height);
  }
  if (o_.fps > 0) {  // best effort: not every driver lets the rate be set
    v4l2_streamparm parm{};
    parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    parm.parm.capture.timeperframe.numerator = 1;
    parm.parm.capture.timeperframe.denominator = uint32_t(o_.fps);
    xioctl(fd_, VIDIOC_S_PARM, &parm);
  }
  v4l2_requestbuffers req{};
  req.count = uint32_t(o_.buffers);
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_REQBUFS, &req) != 0 || req.count < 2) {
    return Error(Errc::kIo, "v4l2: %s: cannot get %d mmap buffers (%s)", dev, o_.buffers,
                 std::strerror(errno));
  }
  const int count = int(req.count) > kMaxBuffers ? kMaxBuffers : int(req.count);
  for (int i = 0; i < count; ++i) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = uint32_t(i);
    if (xioctl(fd_, VIDIOC_QUERYBUF, &b) != 0) {
      return Error(Errc::kIo, "v4l2: %s: QUERYBUF %d: %s", dev, i, std::strerror(errno));
    }
    void* p = mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, b.m.offset);
    if (p == MAP_FAILED) {
      return Error(Errc::kIo, "v4l2: %s: mmap buffer %d: %s", dev, i, std::strerror(errno));
    }
    maps_[i] = p;
    lengths_[i] = b.length;
    mapped_ = i + 1;
    if (xioctl(fd_, VIDIOC_QBUF, &b) != 0) {
      return Error(Errc::kIo, "v4l2: %s: QBUF %d: %s", dev, i, std::strerror(errno));
    }
  }
  v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(fd_, VIDIOC_STREAMON, &type) != 0) {
    return Error(Errc::kIo, "v4l2: %s: STREAMON: %s", dev, std::strerror(errno));
  }
  streaming_ = true;
  return ok();
}

Status V4l2Source::start() {
  Status s = open_device();
  if (!s) {
    error_ = s.error();
    close_device();
  }
  return s;
}

void V4l2Source::stop() {
  close_device();
}

SourceResult V4l2Source::next(FrameBuffer* dst, int64_t timeout_ns) {
  if (!streaming_) {
    // Reopen with back-off; until then the capture thread keeps beating.
    const int64_t now = monotonic_ns();
    if (now < retry_at_ns_) {
      const int64_t wait = retry_at_ns_ - now < timeout_ns ? retry_at_ns_ - now : timeout_ns;
      const timespec ts{time_t(wait / 1000000000), long(wait % 1000000000)};
      nanosleep(&ts, nullptr);
      return SourceResult::kTimeout;
    }
    Status s = open_device();
    if (!s) {
      error_ = s.error();
      close_device();
      retry_at_ns_ = now + retry_delay_ns_;
      if (retry_delay_ns_ < 8 * o_.retry_ns) retry_delay_ns_ *= 2;
      return SourceResult::kFailed;
    }
    ++reopens_;
    retry_delay_ns_ = o_.retry_ns;
  }
  pollfd p{fd_, POLLIN, 0};
  const int r = poll(&p, 1, int(timeout_ns / 1000000));
  if (r == 0) return SourceResult::kTimeout;
  if (r < 0 && errno == EINTR) return SourceResult::kTimeout;
  v4l2_buffer b{};
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  if (r < 0 || (p.revents & (POLLERR | POLLHUP)) || xioctl(fd_, VIDIOC_DQBUF, &b) != 0) {
    const int e = errno;
    if (r > 0 && !(p.revents & (POLLERR | POLLHUP)) && e == EAGAIN) return SourceResult::kTimeout;
    error_ = Error(
        Errc::kIo, "v4l2: %s failed while streaming (%s): closed, reopening with back-off",
        o_.device.c_str(), (p.revents & (POLLERR | POLLHUP)) ? "device gone" : std::strerror(e));
    close_device();
    retry_at_ns_ = monotonic_ns() + retry_delay_ns_;
    return SourceResult::kFailed;
  }
  SourceResult result = SourceResult::kFrame;
  const size_t expect =
      format_ == PixelFormat::kNv12 ? stride_ * size_t(height_) * 3 / 2 : stride_ * size_t(height_);
  if (b.flags & V4L2_BUF_FLAG_ERROR) {
    error_ = Error(Errc::kIo, "v4l2: %s: the driver marked frame %u corrupt", o_.device.c_str(),
                   b.sequence);
    result = SourceResult::kSkipped;
  } else if (decoder_) {
    // MJPEG: the buffer holds one JPEG of bytesused bytes; decode into the slot.
    char what[96];
    std::snprintf(what, sizeof what, "%s frame %u (MJPEG)", o_.device.c_str(), b.sequence);
    auto img = b.index < uint32_t(mapped_) && b.bytesused <= lengths_[b.index]
                   ? decoder_->decode_jpeg_memory(static_cast<const uint8_t*>(maps_[b.index]),
                                                  b.bytesused, dst->data, dst->capacity, what)
                   : Expected<DecodedImage>(Error(Errc::kTruncated, "v4l2: %s: bad buffer", what));
    if (!img) {
      error_ = img.error();
      result = SourceResult::kSkipped;
    } else if (img->width != width_ || img->height != height_) {
      error_ = Error(Errc::kInvalidArgument, "v4l2: %s is %dx%d, the stream %dx%d", what,
                     img->width, img->height, width_, height_);
      result = SourceResult::kSkipped;
    } else {
      fill_info(dst, b, expect);
    }
  } else if (b.bytesused < expect || b.index >= uint32_t(mapped_) || expect > dst->capacity) {
    error_ = Error(Errc::kTruncated, "v4l2: %s: frame %u truncated (%u of %zu bytes)",
                   o_.device.c_str(), b.sequence, b.bytesused, expect);
    result = SourceResult::kSkipped;
  } else {
    std::memcpy(dst->data, maps_[b.index], expect);
    fill_info(dst, b, expect);
  }
  if (xioctl(fd_, VIDIOC_QBUF, &b) != 0) {
    error_ = Error(Errc::kIo, "v4l2: %s: QBUF: %s", o_.device.c_str(), std::strerror(errno));
    close_device();
    retry_at_ns_ = monotonic_ns() + retry_delay_ns_;
    return SourceResult::kFailed;
  }
  return result;
}

}  // namespace aprt
