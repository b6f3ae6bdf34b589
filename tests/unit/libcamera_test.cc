// The libcamera source on a machine without cameras (this one; the HIL rig's
// camera_libcamera scenario streams from a real UVC camera): refusals with
// reasons, an absent camera retried with back-off without ever blocking past
// the timeout, and a build without libcamera saying so.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "drivers/input/camera/libcamera_source.h"

namespace aprt {
namespace {

bool available() {
  auto s = LibcameraSource::create(LibcameraOptions{});
  return s || s.error().code() != Errc::kUnsupported;
}

TEST(Libcamera, RefusesWhatItCannotDeliver) {
  if (!available()) GTEST_SKIP() << "no libcamera in this build";
  LibcameraOptions o;
  o.format = "H264";
  auto a = LibcameraSource::create(o);
  ASSERT_FALSE(a);
  EXPECT_NE(std::strstr(a.error().message(), "NV12"), nullptr) << a.error().message();  // listed
  o.format = "YUYV";
  o.role = "raw";
  auto b = LibcameraSource::create(o);
  ASSERT_FALSE(b);
  EXPECT_NE(std::strstr(b.error().message(), "viewfinder, video, still"), nullptr);
  o.role = "video";
  o.buffers = 1;
  EXPECT_FALSE(LibcameraSource::create(o));
  o.buffers = 4;
  o.format = "MJPEG";
  auto m = LibcameraSource::create(o);
  ASSERT_TRUE(m) << m.error().message();
  EXPECT_EQ(m.value()->max_frame_bytes(), size_t(640) * 480 * 3);  // decoded RGB24
  EXPECT_EQ(m.value()->format(), PixelFormat::kRgb24);
}

TEST(Libcamera, AbsentCameraIsAClearErrorAndRetriedWithBackoff) {
  if (!available()) GTEST_SKIP() << "no libcamera in this build";
  LibcameraOptions o;
  o.camera = "/base/no-such-camera@0";
  o.retry_ns = 200 * 1000000LL;
  auto s = LibcameraSource::create(o);
  ASSERT_TRUE(s) << s.error().message();
  Status st = s.value()->start();
  if (st) GTEST_SKIP() << "a camera with that id exists here";
  EXPECT_EQ(st.error().code(), Errc::kNotFound);
  EXPECT_NE(std::strstr(st.error().message(), "no-such-camera"), nullptr) << st.error().message();
  EXPECT_NE(std::strstr(st.error().message(), "cameras: "), nullptr);  // what there is instead
  std::vector<uint8_t> buf(s.value()->max_frame_bytes());
  FrameBuffer fb;
  fb.data = buf.data();
  fb.capacity = buf.size();
  // Within the back-off: a timeout, bounded by the caller's timeout.
  const int64_t t0 = monotonic_ns();
  EXPECT_EQ(s.value()->next(&fb, 50 * 1000000LL), SourceResult::kTimeout);
  EXPECT_LT(monotonic_ns() - t0, 150 * 1000000LL);
  // After it: a reopen attempt that fails again, with the reason.
  SourceResult r = SourceResult::kTimeout;
  for (int i = 0; i < 10 && r == SourceResult::kTimeout; ++i)
    r = s.value()->next(&fb, 50 * 1000000LL);
  EXPECT_EQ(r, SourceResult::kFailed);
  EXPECT_NE(std::strstr(s.value()->error().message(), "no-such-camera"), nullptr);
  s.value()->stop();
}

TEST(Libcamera, IndexOutOfRange) {
  if (!available()) GTEST_SKIP() << "no libcamera in this build";
  LibcameraOptions o;
  o.camera = "7";
  auto s = LibcameraSource::create(o);
  ASSERT_TRUE(s);
  Status st = s.value()->start();
  if (st) GTEST_SKIP() << "this machine has 8 cameras";
  EXPECT_NE(std::strstr(st.error().message(), "no camera number 7"), nullptr)
      << st.error().message();
}

TEST(Libcamera, BuildWithoutLibcameraSaysSo) {
  if (available()) GTEST_SKIP() << "libcamera is part of this build";
  auto s = LibcameraSource::create(LibcameraOptions{});
  ASSERT_FALSE(s);
  EXPECT_NE(std::strstr(s.error().message(), "libcamera-dev"), nullptr);
}

}  // namespace
}  // namespace aprt
