// The V4L2 source without a camera (this machine has none; the HIL rig's
// vivid scenario streams from a real driver): refusals with reasons, and a
// missing device retried with back-off without ever blocking past the timeout.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "drivers/camera/v4l2_source.h"

namespace aprt {
namespace {

TEST(V4l2, RefusesWhatItCannotDeliver) {
  V4l2Options o;
  o.format = "MJPEG";
  auto a = V4l2Source::create(o);
  ASSERT_FALSE(a);
  EXPECT_NE(std::strstr(a.error().message(), "MJPEG"), nullptr) << a.error().message();
  o.format = "YUYV";
  o.buffers = 1;
  auto b = V4l2Source::create(o);
  ASSERT_FALSE(b);
  EXPECT_NE(std::strstr(b.error().message(), "buffers"), nullptr);
}

TEST(V4l2, MissingDeviceIsAClearErrorAndRetriedWithBackoff) {
  V4l2Options o;
  o.device = "/dev/aprt-no-such-video";
  o.retry_ns = 200 * 1000000LL;
  auto s = V4l2Source::create(o);
  ASSERT_TRUE(s) << s.error().message();
  EXPECT_GE(s.value()->max_frame_bytes(), size_t(640 * 480 * 2));
  Status st = s.value()->start();
  ASSERT_FALSE(st);
  EXPECT_EQ(st.error().code(), Errc::kNotFound);
  EXPECT_NE(std::strstr(st.error().message(), "/dev/aprt-no-such-video"), nullptr);

  std::vector<uint8_t> buf(s.value()->max_frame_bytes());
  FrameBuffer fb;
  fb.data = buf.data();
  fb.capacity = buf.size();
  // First next(): a reopen attempt fails at once; then it waits for the
  // back-off, but never longer than the timeout it is given.
  EXPECT_EQ(s.value()->next(&fb, 50 * 1000000LL), SourceResult::kFailed);
  const int64_t t0 = monotonic_ns();
  EXPECT_EQ(s.value()->next(&fb, 50 * 1000000LL), SourceResult::kTimeout);
  const int64_t waited = monotonic_ns() - t0;
  EXPECT_LT(waited, 1000 * 1000000LL);  // bounded by the timeout (loose: shared CI machine)
  EXPECT_EQ(s.value()->reopens(), 0u);
}

TEST(V4l2, ANonCameraIsRefusedWithWhatItIs) {
  V4l2Options o;
  o.device = "/dev/null";
  auto s = V4l2Source::create(o);
  ASSERT_TRUE(s);
  Status st = s.value()->start();
  ASSERT_FALSE(st);
  EXPECT_NE(std::strstr(st.error().message(), "not a V4L2 device"), nullptr)
      << st.error().message();
}

}  // namespace
}  // namespace aprt
