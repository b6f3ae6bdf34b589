// The V4L2 source without a camera (this machine has none; the HIL rig's
// vivid scenario streams from a real driver): refusals with reasons, and a
// missing device retried with back-off without ever blocking past the timeout.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

// jpeglib.h needs FILE and size_t declared first.
#include <jpeglib.h>

#include "drivers/codec/image_decoder.h"
#include "drivers/input/camera/v4l2_devices.h"
#include "drivers/input/camera/v4l2_source.h"
#include "drivers/input/replay/deeploc_replay.h"

namespace aprt {
namespace {

TEST(V4l2, RefusesWhatItCannotDeliver) {
  V4l2Options o;
  o.format = "H264";
  auto a = V4l2Source::create(o);
  ASSERT_FALSE(a);
  EXPECT_NE(std::strstr(a.error().message(), "MJPEG"), nullptr) << a.error().message();  // listed
  o.format = "MJPEG";
  auto m = V4l2Source::create(o);
  ASSERT_TRUE(m) << m.error().message();
  EXPECT_EQ(m.value()->max_frame_bytes(), size_t(640) * 480 * 3 + 4096);  // decoded RGB24
  o.format = "YUYV";
  o.buffers = 1;
  auto b = V4l2Source::create(o);
  ASSERT_FALSE(b);
  EXPECT_NE(std::strstr(b.error().message(), "buffers"), nullptr);
}

TEST(V4l2, ByCardNameOrBusInfo) {
  char path[256];
  // A path is used as it is.
  ASSERT_TRUE(resolve_v4l2_device("/dev/v4l/by-id/usb-cam-video-index0", path, sizeof path));
  EXPECT_STREQ(path, "/dev/v4l/by-id/usb-cam-video-index0");
  // A name no capture node has: refused, with what there is (the HIL VM's
  // camera_vivid scenario opens vivid by its card name).
  Status s = resolve_v4l2_device("aprt test camera that is not there", path, sizeof path);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code(), Errc::kNotFound);
  EXPECT_NE(std::strstr(s.error().message(), "'aprt test camera that is not there'"), nullptr);
  EXPECT_NE(std::strstr(s.error().message(), "found: "), nullptr) << s.error().message();
  // And the source reports it from start(), retrying like a missing path.
  V4l2Options o;
  o.device = "aprt test camera that is not there";
  auto src = V4l2Source::create(o);
  ASSERT_TRUE(src) << src.error().message();
  Status st = src.value()->start();
  ASSERT_FALSE(st);
  EXPECT_NE(std::strstr(st.error().message(), "card name or bus_info"), nullptr);
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

// What the MJPEG path decodes a camera's buffer with: a JPEG in memory into
// the slot; corrupt and truncated frames refused (libjpeg would otherwise
// fill the missing part with grey and report success).
std::vector<uint8_t> encode_jpeg(int w, int h) {
  std::vector<uint8_t> rgb(size_t(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      uint8_t* p = &rgb[(size_t(y) * w + x) * 3];
      p[0] = uint8_t(x * 4), p[1] = uint8_t(y * 4), p[2] = uint8_t(128);
    }
  jpeg_compress_struct c{};
  jpeg_error_mgr err{};
  c.err = jpeg_std_error(&err);
  jpeg_create_compress(&c);
  unsigned char* out = nullptr;
  unsigned long size = 0;
  jpeg_mem_dest(&c, &out, &size);
  c.image_width = JDIMENSION(w);
  c.image_height = JDIMENSION(h);
  c.input_components = 3;
  c.in_color_space = JCS_RGB;
  jpeg_set_defaults(&c);
  jpeg_set_quality(&c, 95, TRUE);
  jpeg_start_compress(&c, TRUE);
  while (c.next_scanline < c.image_height) {
    JSAMPROW row = &rgb[size_t(c.next_scanline) * w * 3];
    jpeg_write_scanlines(&c, &row, 1);
  }
  jpeg_finish_compress(&c);
  std::vector<uint8_t> bytes(out, out + size);
  jpeg_destroy_compress(&c);
  std::free(out);
  return bytes;
}

TEST(Mjpeg, DecodesFromMemoryAndRefusesDamage) {
  auto d = ImageDecoder::create(1, 4096);
  ASSERT_TRUE(d) << d.error().message();
  const std::vector<uint8_t> jpg = encode_jpeg(64, 48);
  std::vector<uint8_t> out(64 * 48 * 3);
  auto img = d.value()->decode_jpeg_memory(jpg.data(), jpg.size(), out.data(), out.size(), "f1");
  ASSERT_TRUE(img) << img.error().message();
  EXPECT_EQ(img->width, 64);
  EXPECT_EQ(img->height, 48);
  const uint8_t* p = &out[(size_t(20) * 64 + 30) * 3];
  EXPECT_NEAR(p[0], 120, 6);
  EXPECT_NEAR(p[1], 80, 6);
  EXPECT_NEAR(p[2], 128, 6);

  // Cut inside the entropy-coded data (libjpeg's "premature end" warning).
  auto cut = d.value()->decode_jpeg_memory(jpg.data(), jpg.size() - jpg.size() / 5, out.data(),
                                           out.size(), "f2");
  ASSERT_FALSE(cut);
  EXPECT_NE(std::strstr(cut.error().message(), "corrupt or truncated JPEG"), nullptr)
      << cut.error().message();
  std::vector<uint8_t> junk(jpg.size(), 0x55);
  auto bad = d.value()->decode_jpeg_memory(junk.data(), junk.size(), out.data(), out.size(), "f3");
  ASSERT_FALSE(bad);
  EXPECT_NE(std::strstr(bad.error().message(), "f3: not a JPEG"), nullptr);
  auto small = d.value()->decode_jpeg_memory(jpg.data(), jpg.size(), out.data(), 100, "f4");
  ASSERT_FALSE(small);
  // The decoder is usable after every failure.
  EXPECT_TRUE(d.value()->decode_jpeg_memory(jpg.data(), jpg.size(), out.data(), out.size(), "f5"));
}

// A replay's first frame sizes the frame slot. A 600-byte JPEG whose header
// claims 16000x16000 took 2.3 GB there, and every real frame after it was
// skipped (0 poses, exit 0): refused at open now, with the reason.
TEST(Replay, AFirstFrameClaimingAHugeSizeIsRefused) {
  char dir[] = "/tmp/aprt_replay_XXXXXX";
  ASSERT_NE(mkdtemp(dir), nullptr);
  std::vector<uint8_t> jpeg = encode_jpeg(16, 16);
  bool patched = false;  // SOF0: FF C0, length, precision, height, width
  for (size_t i = 0; i + 9 < jpeg.size() && !patched; ++i) {
    if (jpeg[i] == 0xFF && jpeg[i + 1] == 0xC0) {
      jpeg[i + 5] = 0x3E, jpeg[i + 6] = 0x80;  // 16000
      jpeg[i + 7] = 0x3E, jpeg[i + 8] = 0x80;
      patched = true;
    }
  }
  ASSERT_TRUE(patched);
  const std::string d = dir;
  FILE* f = std::fopen((d + "/bomb.jpg").c_str(), "wb");
  ASSERT_NE(f, nullptr);
  std::fwrite(jpeg.data(), 1, jpeg.size(), f);
  std::fclose(f);
  f = std::fopen((d + "/poses.txt").c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fputs("bomb.jpg 0 0 0 1 0 0 0\n", f);
  std::fclose(f);
  auto r = DeeplocReplay::open(dir);
  ASSERT_FALSE(r);
  EXPECT_NE(std::strstr(r.error().message(), "claims 16000x16000 pixels, more than the 4096x4096"),
            nullptr)
      << r.error().message();
  std::remove((d + "/bomb.jpg").c_str());
  std::remove((d + "/poses.txt").c_str());
  rmdir(dir);
}

}  // namespace
}  // namespace aprt
