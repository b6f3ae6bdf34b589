// The MCAP writer and the ROS 2 CDR messages: the file's structure walked
// record by record here (magic at both ends, every length, the footer's
// offsets, the statistics), CDR alignment checked against hand-built bytes,
// and a sample file for the independent readers (tests/tools/mcap_check.js:
// npm @mcap/core and @foxglove/rosmsg2-serialization decode it).
#include "drivers/codec/mcap_writer.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "drivers/codec/mcap_reader.h"
#include "drivers/codec/ros2_cdr.h"
#include "runtime/base/crc32.h"

namespace aprt {
namespace {

std::vector<uint8_t> read_all(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

template <typename T>
T at(const std::vector<uint8_t>& b, size_t off) {
  T v;
  std::memcpy(&v, b.data() + off, sizeof v);
  return v;
}

// The sample every reader checks: 3 images, 3 poses, 2 diagnostics, 2 clouds.
std::string write_sample(const std::string& path, bool with_large_image = true) {
  auto w = McapWriter::create(path.c_str(), "aprt test");
  EXPECT_TRUE(w) << w.error().message();
  McapWriter& m = *w.value();
  const uint16_t s_img =
      m.add_schema("sensor_msgs/msg/Image", "ros2msg", ros2::kImageDefinition).value();
  const uint16_t s_pose = m.add_schema("geometry_msgs/msg/PoseWithCovarianceStamped", "ros2msg",
                                       ros2::kPoseWithCovarianceStampedDefinition)
                              .value();
  const uint16_t s_diag = m.add_schema("diagnostic_msgs/msg/DiagnosticArray", "ros2msg",
                                       ros2::kDiagnosticArrayDefinition)
                              .value();
  const uint16_t s_pc =
      m.add_schema("sensor_msgs/msg/PointCloud2", "ros2msg", ros2::kPointCloud2Definition).value();
  const uint16_t c_img = m.add_channel(s_img, "/aprt/image", "cdr").value();
  const uint16_t c_pose = m.add_channel(s_pose, "/aprt/pose_with_covariance", "cdr").value();
  const uint16_t c_diag = m.add_channel(s_diag, "/diagnostics", "cdr").value();
  const uint16_t c_pc = m.add_channel(s_pc, "/points_raw", "cdr").value();
  std::vector<uint8_t> buf(1 << 20);
  const int64_t t0 = 1796000000LL * 1000000000LL + 5;
  for (int i = 0; i < 3; ++i) {
    std::vector<uint8_t> px(5 * 3 * 3);  // 5x3 rgb8, odd width: no row padding
    for (size_t k = 0; k < px.size(); ++k) px[k] = uint8_t(k * 7 + i);
    const int64_t t = t0 + i * 40000000LL;
    size_t n =
        ros2::image(buf.data(), buf.size(), t, "camera", 5, 3, "rgb8", 15, px.data(), px.size());
    EXPECT_GT(n, 0u);
    EXPECT_TRUE(m.write_message(c_img, uint64_t(t), uint64_t(t), buf.data(), n));
    const double pos[3] = {100.5 + i, -20.25, 1.5};
    const double q[4] = {0.5, 0.5, -0.5, 0.5};  // w x y z
    double cov[36] = {};
    for (int k = 0; k < 36; k += 7) cov[k] = 0.25 * (k + 1);
    n = ros2::pose_with_covariance(buf.data(), buf.size(), t, "map", pos, q, cov);
    EXPECT_TRUE(m.write_message(c_pose, uint64_t(t + 1000), uint64_t(t), buf.data(), n));
  }
  for (int i = 0; i < 2; ++i) {
    const char* keys[2] = {"state", "poses"};
    const char* vals[2] = {i ? "RUNNING" : "STARTING", i ? "2" : "0"};
    const int64_t t = t0 + i * 1000000000LL;
    const size_t n =
        ros2::diagnostics(buf.data(), buf.size(), t, "map", uint8_t(i ? 0 : 1), "aprt: pose",
                          i ? "RUNNING: ok" : "STARTING: starting", "aprt", keys, vals, 2);
    EXPECT_TRUE(m.write_message(c_diag, uint64_t(t), uint64_t(t), buf.data(), n));
    const float pts[8] = {1.0f, 2.0f, 3.0f, 0.5f, -1.0f, -2.0f, 0.25f, 9.0f};
    const size_t k = ros2::pointcloud2_xyzi(buf.data(), buf.size(), t, "lidar", pts, 2);
    EXPECT_TRUE(m.write_message(c_pc, uint64_t(t), uint64_t(t), buf.data(), k));
  }
  if (!with_large_image) {  // the fuzzer's seed: small
    EXPECT_TRUE(m.close());
    return path;
  }
  // A message larger than the writer's buffer goes straight to the file.
  std::vector<uint8_t> big(640 * 480 * 3, 0x5a);
  const size_t n = ros2::image(buf.data(), buf.size(), t0 + 200000000LL, "camera", 640, 480, "rgb8",
                               1920, big.data(), big.size());
  EXPECT_TRUE(m.write_message(c_img, uint64_t(t0 + 200000000LL), uint64_t(t0 + 200000000LL),
                              buf.data(), n));
  EXPECT_EQ(m.messages(), 11u);
  EXPECT_TRUE(m.close());
  return path;
}

TEST(Mcap, TheFileIsWellFormedRecordByRecord) {
  const std::string path = testing::TempDir() + "/aprt_mcap_test.mcap";
  write_sample(path);
  const auto b = read_all(path);
  ASSERT_GT(b.size(), 16u);
  const uint8_t magic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
  EXPECT_EQ(std::memcmp(b.data(), magic, 8), 0);
  EXPECT_EQ(std::memcmp(b.data() + b.size() - 8, magic, 8), 0);
  // Walk: every record's length lands on the next opcode, the footer last.
  size_t off = 8, messages = 0, data_end = 0;
  std::vector<uint8_t> ops;
  while (off + 9 <= b.size() - 8) {
    const uint8_t op = b[off];
    const uint64_t len = at<uint64_t>(b, off + 1);
    ASSERT_LE(off + 9 + len, b.size() - 8) << "record at " << off;
    ops.push_back(op);
    if (op == 0x05) ++messages;
    if (op == 0x0F) {
      data_end = off;
      // Its CRC covers every byte before it, the leading magic included.
      EXPECT_EQ(at<uint32_t>(b, off + 9), crc32(b.data(), off));
    }
    if (op == 0x02) {
      const uint64_t summary = at<uint64_t>(b, off + 9);
      const uint64_t offsets = at<uint64_t>(b, off + 17);
      EXPECT_EQ(summary, data_end + 9 + 4);
      EXPECT_EQ(b[summary], 0x03);  // the summary starts with the schemas
      EXPECT_EQ(b[offsets], 0x0E);
      EXPECT_EQ(at<uint32_t>(b, off + 25), crc32(b.data() + summary, off + 25 - summary));
    }
    off += 9 + len;
  }
  EXPECT_EQ(off, b.size() - 8);
  EXPECT_EQ(messages, 11u);
  ASSERT_FALSE(ops.empty());
  EXPECT_EQ(ops.front(), 0x01);
  EXPECT_EQ(ops.back(), 0x02);
  std::remove(path.c_str());
}

TEST(Mcap, CdrAlignmentIsRos2s) {
  // A pose: header (stamp 8, frame_id "map": 4 + 4 bytes), then doubles on 8.
  uint8_t buf[512];
  const double p[3] = {1, 2, 3}, q[4] = {1, 0, 0, 0};
  double cov[36] = {};
  const size_t n = ros2::pose_with_covariance(buf, sizeof buf, 1500000000, "map", p, q, cov);
  EXPECT_EQ(n, 4u + 8 + 8 + 7 * 8 + 36 * 8);
  EXPECT_EQ(buf[1], 0x01);  // CDR_LE
  EXPECT_EQ(at<int32_t>(std::vector<uint8_t>(buf, buf + n), 4), 1);
  EXPECT_EQ(at<uint32_t>(std::vector<uint8_t>(buf, buf + n), 8), 500000000u);
  EXPECT_EQ(std::memcmp(buf + 16, "map", 4), 0);
  EXPECT_EQ(at<double>(std::vector<uint8_t>(buf, buf + n), 20), 1.0);
  EXPECT_EQ(at<double>(std::vector<uint8_t>(buf, buf + n), 20 + 6 * 8), 1.0);  // w after x y z
  // "camera" (7 bytes with NUL) leaves the next u32 padded to 4.
  uint8_t px[3] = {1, 2, 3};
  const size_t k = ros2::image(buf, sizeof buf, 0, "camera", 1, 1, "rgb8", 3, px, 3);
  EXPECT_EQ(k, 4u + 8 + 4 + 7 + 1 + 4 + 4 + 4 + 5 + 3 + 4 + 4 + 3);
  EXPECT_EQ(ros2::image(buf, 16, 0, "camera", 1, 1, "rgb8", 3, px, 3), 0u);  // too small: 0
}

TEST(Mcap, RefusalsSayWhat) {
  const std::string path = testing::TempDir() + "/aprt_mcap_refusals.mcap";
  auto w = McapWriter::create(path.c_str(), "aprt test");
  ASSERT_TRUE(w);
  EXPECT_FALSE(w.value()->add_channel(3, "/x", "cdr"));
  EXPECT_FALSE(w.value()->write_message(1, 0, 0, "x", 1));
  EXPECT_FALSE(McapWriter::create("/nonexistent/dir/x.mcap", "aprt"));
  std::remove(path.c_str());
}

// Writes the sample for the independent readers when asked (ctest fixture);
// APRT_MCAP_SEED: the small one the fuzzer's corpus holds (tests/fuzz/corpus/mcap).
TEST(Mcap, WriteSampleForIndependentReaders) {
  const char* out = std::getenv("APRT_MCAP_SAMPLE");
  const char* seed = std::getenv("APRT_MCAP_SEED");
  if (!out && !seed) GTEST_SKIP() << "APRT_MCAP_SAMPLE not set";
  if (out) write_sample(out);
  if (seed) write_sample(seed, false);
}

// The reader on what aprt writes, on a recording cut short, and on files it refuses.
TEST(Mcap, ReaderReadsItsOwnFilesAndRefusesWithReasons) {
  const std::string path = testing::TempDir() + "/aprt_mcap_reader.mcap";
  write_sample(path);
  const std::vector<std::string> kinds = {"sensor_msgs/msg/Image", "sensor_msgs/msg/PointCloud2"};
  {
    auto r = McapReader::open(path.c_str(), "", kinds);
    ASSERT_TRUE(r) << r.error().message();
    EXPECT_EQ(r.value()->channel().topic, "/aprt/image");
    EXPECT_EQ(r.value()->size(), 4u);
    EXPECT_FALSE(r.value()->truncated());
    size_t n = 0;
    auto b = r.value()->read(1, &n);
    ASSERT_TRUE(b);
    ros2::ImageMsg img;
    ASSERT_TRUE(ros2::read_image(b.value(), n, &img));
    EXPECT_EQ(img.width, 5u);
    EXPECT_STREQ(img.encoding, "rgb8");
    EXPECT_EQ(img.data[0], 1);  // k * 7 + i, i = 1
    EXPECT_EQ(img.stamp_ns, 1796000000LL * 1000000000LL + 5 + 40000000LL);
    EXPECT_FALSE(ros2::read_pointcloud2(b.value(), n, &*std::make_unique<ros2::PointCloud2Msg>()));
  }
  {
    auto r = McapReader::open(path.c_str(), "/points_raw", kinds);
    ASSERT_TRUE(r) << r.error().message();
    size_t n = 0;
    auto b = r.value()->read(0, &n);
    ASSERT_TRUE(b);
    ros2::PointCloud2Msg pc;
    ASSERT_TRUE(ros2::read_pointcloud2(b.value(), n, &pc));
    EXPECT_EQ(pc.width, 2u);
    EXPECT_EQ(pc.n_fields, 4);
    EXPECT_STREQ(pc.fields[3].name, "intensity");
  }
  auto none = McapReader::open(path.c_str(), "/nothing", kinds);
  ASSERT_FALSE(none);
  EXPECT_NE(std::string(none.error().message()).find("/aprt/image (sensor_msgs/msg/Image)"),
            std::string::npos)
      << none.error().message();  // the channels it has are listed
  // Cut inside the large image: the whole records before it are kept.
  auto bytes = read_all(path);
  const std::string cut = testing::TempDir() + "/aprt_mcap_cut.mcap";
  std::ofstream(cut, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size() - 400000));
  {
    auto r = McapReader::open(cut.c_str(), "", kinds);
    ASSERT_TRUE(r) << r.error().message();
    EXPECT_TRUE(r.value()->truncated());
    EXPECT_EQ(r.value()->size(), 3u);
  }
  // Not MCAP; a chunk record.
  std::ofstream(cut, std::ios::binary) << "not an mcap file at all";
  auto bad = McapReader::open(cut.c_str(), "", kinds);
  ASSERT_FALSE(bad);
  EXPECT_NE(std::string(bad.error().message()).find("not an MCAP file"), std::string::npos);
  std::vector<uint8_t> chunked(bytes.begin(), bytes.begin() + 8);
  const uint8_t chunk[9] = {0x06, 4, 0, 0, 0, 0, 0, 0, 0};
  chunked.insert(chunked.end(), chunk, chunk + 9);
  chunked.insert(chunked.end(), 4, 0);
  std::ofstream(cut, std::ios::binary)
      .write(reinterpret_cast<const char*>(chunked.data()), std::streamsize(chunked.size()));
  auto ch = McapReader::open(cut.c_str(), "", kinds);
  ASSERT_FALSE(ch);
  EXPECT_NE(std::string(ch.error().message()).find("chunked"), std::string::npos);
  std::remove(cut.c_str());
  std::remove(path.c_str());
}

}  // namespace
}  // namespace aprt
