// The line-oriented files aprt reads from outside: pose lists and times of a
// replay, the sidecar of a saved frame. Each case is a reproducer of a file
// that was once accepted (docs/hostile_input.md); the fuzz targets in
// tests/fuzz/ explore the rest.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "drivers/codec/frame_sidecar.h"
#include "drivers/input/replay/pose_list.h"
#include "runtime/base/text_lines.h"

namespace aprt {
namespace {

template <class T>
void expect_error(const Expected<T>& r, const char* fragment) {
  ASSERT_FALSE(r) << "accepted";
  EXPECT_NE(std::strstr(r.error().message(), fragment), nullptr) << r.error().message();
}

TEST(TextLines, IntegersAreDecimalAndBounded) {
  int64_t v = 0;
  EXPECT_TRUE(parse_integer("640", 1, 1000, &v));
  EXPECT_EQ(v, 640);
  EXPECT_TRUE(parse_integer("-3", -5, 5, &v));
  for (const char* bad : {"", "-", "0x10", " 5", "5 ", "+5", "1e3", "99999999999999999999", "1001"})
    EXPECT_FALSE(parse_integer(bad, 1, 1000, &v)) << bad;
  double d = 0;
  EXPECT_TRUE(parse_finite("1.5e3", &d));
  for (const char* bad : {"nan", "inf", "1e999", "1.5x", ""}) EXPECT_FALSE(parse_finite(bad, &d));
}

TEST(PoseList, ReadsNamesAndNormalisesQuaternions) {
  std::vector<ReplayEntry> e;
  ASSERT_TRUE(parse_pose_list("# comment\na.png 1 2 3 2 0 0 0\n\nb.png 4 5 6 0 0 0 3\n", "p", &e));
  ASSERT_EQ(e.size(), 2u);
  EXPECT_STREQ(e[1].name, "b.png");
  EXPECT_DOUBLE_EQ(e[0].orientation[0], 1.0);
  EXPECT_DOUBLE_EQ(e[1].orientation[3], 1.0);
  ASSERT_TRUE(parse_times("a.png 0.5\nb.png 0.6\n", "t", &e));
  EXPECT_DOUBLE_EQ(e[1].time_s, 0.6);
}

TEST(PoseList, MalformedListsAreRefusedWithTheLine) {
  auto refused = [](const char* text, const char* fragment) {
    std::vector<ReplayEntry> e;
    Status s = parse_pose_list(text, "poses.txt", &e);
    ASSERT_FALSE(s) << text;
    EXPECT_NE(std::strstr(s.error().message(), fragment), nullptr) << s.error().message();
  };
  refused("a 1 2 3 1 0 0 0 garbage\n", "poses.txt:1: expected 'name x y z qw qx qy qz'");
  refused("a 1 2 3 1 0 0 0\nb 1 2 3x 1 0 0 0\n", "poses.txt:2: '3x' is not a finite number");
  refused("a nan 2 3 1 0 0 0\n", "'nan' is not a finite number");
  refused("a 1 2 3 0 0 0 0\n", "zero quaternion");
  // Found by fuzzing: squares that overflow made a "normalised" quaternion of zeros.
  refused("a 1 2 3 0.7 -0.01e217 0.01 0.7\n", "quaternion component -1e+215");
  refused("a 1e30 2 3 1 0 0 0\n", "coordinate 1e+30 m is beyond");
  refused("# only a comment\n", "lists no frames");
  refused((std::string(2000, 'a') + " 1 2 3 1 0 0 0\n").c_str(), "a line of 2014 bytes");
  static const char kNul[] = "a 1 2 3 1 0 0 0\nb\0 1 2 3 1 0 0 0\n";
  std::vector<ReplayEntry> e;
  Status s = parse_pose_list(std::string_view(kNul, sizeof kNul - 1), "p", &e);
  ASSERT_FALSE(s);
  EXPECT_NE(std::strstr(s.error().message(), "p:2: a NUL byte"), nullptr) << s.error().message();
}

TEST(PoseList, TimesMustMatchAndIncrease) {
  std::vector<ReplayEntry> e;
  ASSERT_TRUE(parse_pose_list("a 0 0 0 1 0 0 0\nb 0 0 0 1 0 0 0\n", "p", &e));
  auto refused = [&](const char* text, const char* fragment) {
    std::vector<ReplayEntry> copy = e;
    Status s = parse_times(text, "times.txt", &copy);
    ASSERT_FALSE(s) << text;
    EXPECT_NE(std::strstr(s.error().message(), fragment), nullptr) << s.error().message();
  };
  refused("a 1.0\nb 0.5\n", "times.txt:2: 0.5 s is not after the previous frame's 1 s");
  refused("a 1.0\nb nan\n", "'nan' is not a finite number of seconds");
  refused("a 1.0\nc 2.0\n", "'c' where the pose list has 'b'");
  refused("a 1.0\n", "times for 1 of the 2 frames");
  refused("a 1.0\nb 2.0\nc 3.0\n", "more times than the 2 frames");
}

FrameSidecar small_rgb() {
  FrameSidecar s;
  s.format = PixelFormat::kRgb24;
  s.width = 64;
  s.height = 48;
  s.stride = 64 * 3;
  s.bytes = s.stride * 48;
  s.have_pose = true;
  const double pose[7] = {1.5, -2.25, 0.5, 1, 0, 0, 0};
  std::copy(pose, pose + 7, s.pose);
  return s;
}

TEST(FrameSidecar, RoundTrips) {
  const FrameSidecar s = small_rgb();
  auto back = parse_frame_sidecar(format_frame_sidecar(s, "f.png", "m.aprt", "avx512", 4), "x");
  ASSERT_TRUE(back) << back.error().message();
  EXPECT_EQ(back.value().width, 64);
  EXPECT_EQ(back.value().stride, 192u);
  EXPECT_TRUE(back.value().have_pose);
  EXPECT_DOUBLE_EQ(back.value().pose[1], -2.25);
}

TEST(FrameSidecar, AStrideOrSizeThatDoesNotHoldTheFrameIsRefused) {
  const std::string head = "format RGB24\nwidth 64\nheight 48\n";
  // The reproducer: a stride larger than the bytes hold made aprt infer read
  // past its buffer (ASan: heap use-after-free; release: a pose 99 m off).
  expect_error(parse_frame_sidecar(head + "stride 100000\nbytes 9216\n", "f.txt"),
               "stride 100000 for 64 RGB24 pixels a row");
  expect_error(parse_frame_sidecar(head + "stride 1000\nbytes 9216\n", "f.txt"),
               "9216 bytes cannot hold 64x48 RGB24 rows 1000 bytes apart");
  expect_error(parse_frame_sidecar(head + "stride 100\nbytes 9216\n", "f.txt"),
               "stride 100 for 64 RGB24 pixels a row (at least 192");
  expect_error(parse_frame_sidecar(head + "stride 192\nbytes 9215\n", "f.txt"), "cannot hold");
  expect_error(
      parse_frame_sidecar("format NV12\nwidth 64\nheight 48\nstride 64\nbytes 4096\n", "f.txt"),
      "4096 bytes cannot hold 64x48 NV12");
  EXPECT_TRUE(
      parse_frame_sidecar("format NV12\nwidth 64\nheight 48\nstride 64\nbytes 4608\n", "f"));
}

TEST(FrameSidecar, MalformedTextIsRefusedWithTheLine) {
  const std::string ok = "format RGB24\nwidth 64\nheight 48\nstride 192\nbytes 9216\n";
  expect_error(parse_frame_sidecar("format RGB24\nwidth 64\n", "f.txt"), "lacks one of");
  expect_error(parse_frame_sidecar(ok + "width 32\n", "f.txt"), "f.txt:6: 'width' given twice");
  expect_error(parse_frame_sidecar("format rgba\n", "f.txt"), "unknown pixel format 'rgba'");
  expect_error(parse_frame_sidecar("width -64\n", "f.txt"), "'width' needs one integer in [1,");
  expect_error(parse_frame_sidecar("width 0x40\n", "f.txt"), "'width' needs one integer");
  expect_error(parse_frame_sidecar("width 99999\n", "f.txt"), "'width' needs one integer");
  expect_error(parse_frame_sidecar(ok + "pose 1 2 3 1 0 0\n", "f.txt"), "'pose' needs 7 numbers");
  expect_error(parse_frame_sidecar(ok + "pose 1 2 inf 1 0 0 0\n", "f.txt"),
               "'inf' is not a finite number");
  EXPECT_TRUE(parse_frame_sidecar(ok + "comment from a later version\n", "f.txt"));
}

}  // namespace
}  // namespace aprt
