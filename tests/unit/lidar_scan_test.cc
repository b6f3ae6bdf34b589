// LiDAR scans from files (drivers/lidar): KITTI .bin and PCD (ascii and
// binary, fields in any order, other fields beside them), through the point
// gate -- NaN/Inf dropped, absurd values clipped, the count bounded -- and
// files that lie about themselves refused with the reason; labelled sequences
// (lidar_poses.txt naming scans).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "drivers/input/lidar/lidar_sequence.h"
#include "drivers/input/lidar/scan_reader.h"

namespace aprt {
namespace {

std::string temp(const char* name) {
  return ::testing::TempDir() + name;
}

void write_bytes(const std::string& path, const void* p, size_t n) {
  std::ofstream(path, std::ios::binary).write(static_cast<const char*>(p), long(n));
}

struct Fixture {
  std::unique_ptr<ScanReader> reader = std::move(ScanReader::create().value());
  std::unique_ptr<PointCloud> cloud = std::move(PointCloud::create(4).value());
  PointRegion region;
};

TEST(LidarScan, KittiBinThroughTheGate) {
  Fixture f;
  const float pts[] = {1,    2,        3,  0.5f,  // kept
                       NAN,  0,        0,  1,     // dropped: NaN
                       0,    INFINITY, 0,  1,     // dropped: Inf
                       1e9f, -5,       0,  1,     // clipped to x_max
                       4,    5,        6,  NAN,   // kept, intensity 0
                       7,    8,        9,  1,    10, 11,
                       12,   1,        13, 14,   15, 1};  // the last over capacity
  const std::string path = temp("scan.bin");
  write_bytes(path, pts, sizeof pts);
  ASSERT_TRUE(f.reader->read(path.c_str(), f.region, f.cloud.get()));
  const ScanStats& s = f.cloud->stats();
  EXPECT_EQ(s.read, 8u);
  EXPECT_EQ(s.non_finite, 2u);
  EXPECT_EQ(s.clipped, 1u);
  EXPECT_EQ(s.over_capacity, 2u);
  ASSERT_EQ(f.cloud->size(), 4u);
  EXPECT_EQ(f.cloud->points()[1].x, f.region.x_max);
  EXPECT_EQ(f.cloud->points()[2].intensity, 0.0f);
  // Not a whole number of points: refused.
  write_bytes(path, pts, sizeof pts - 3);
  Status t = f.reader->read(path.c_str(), f.region, f.cloud.get());
  ASSERT_FALSE(t);
  EXPECT_NE(std::strstr(t.error().message(), "truncated?"), nullptr) << t.error().message();
}

TEST(LidarScan, PcdAsciiAndBinary) {
  Fixture f;
  f.cloud = std::move(PointCloud::create(100).value());
  const std::string a = temp("scan_ascii.pcd");
  std::ofstream(a) << "# .PCD v0.7\nVERSION 0.7\nFIELDS intensity x ring y z\nSIZE 4 4 2 4 4\n"
                      "TYPE F F U F F\nCOUNT 1 1 1 1 1\nWIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA ascii\n"
                      "0.5 1 7 2 3\n0.25 4 8 5 nan\n1 7 9 8 9\n";
  ASSERT_TRUE(f.reader->read(a.c_str(), f.region, f.cloud.get()));
  ASSERT_EQ(f.cloud->size(), 2u);
  EXPECT_EQ(f.cloud->stats().non_finite, 1u);
  EXPECT_EQ(f.cloud->points()[0].x, 1.0f);
  EXPECT_EQ(f.cloud->points()[0].y, 2.0f);
  EXPECT_EQ(f.cloud->points()[0].z, 3.0f);
  EXPECT_EQ(f.cloud->points()[0].intensity, 0.5f);
  EXPECT_EQ(f.cloud->points()[1].x, 7.0f);

  // Binary: x as double, an extra field, no intensity; many points across reads.
  const std::string b = temp("scan_binary.pcd");
  const int n = 20000;
  std::string header =
      "VERSION 0.7\nFIELDS x y z t\nSIZE 8 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n"
      "WIDTH " +
      std::to_string(n) + "\nHEIGHT 1\nPOINTS " + std::to_string(n) + "\nDATA binary\n";
  std::vector<char> body(size_t(n) * 20);
  for (int i = 0; i < n; ++i) {
    const double x = i * 0.001;
    const float y = float(-i) * 0.001f, z = 1.5f;
    const uint32_t t = uint32_t(i);
    std::memcpy(&body[size_t(i) * 20], &x, 8);
    std::memcpy(&body[size_t(i) * 20 + 8], &y, 4);
    std::memcpy(&body[size_t(i) * 20 + 12], &z, 4);
    std::memcpy(&body[size_t(i) * 20 + 16], &t, 4);
  }
  {
    std::ofstream o(b, std::ios::binary);
    o << header;
    o.write(body.data(), long(body.size()));
  }
  auto big = std::move(PointCloud::create(size_t(n)).value());
  ASSERT_TRUE(f.reader->read(b.c_str(), f.region, big.get()));
  ASSERT_EQ(big->size(), size_t(n));
  EXPECT_FLOAT_EQ(big->points()[n - 1].x, float((n - 1) * 0.001));
  EXPECT_FLOAT_EQ(big->points()[n - 1].y, float(-(n - 1)) * 0.001f);
  EXPECT_EQ(big->points()[n - 1].intensity, 0.0f);
  // Truncated: the header's count is checked.
  {
    std::ofstream o(b, std::ios::binary);
    o << header;
    o.write(body.data(), long(body.size() / 2));
  }
  Status t = f.reader->read(b.c_str(), f.region, big.get());
  ASSERT_FALSE(t);
  EXPECT_NE(std::strstr(t.error().message(), "truncated?"), nullptr) << t.error().message();
}

TEST(LidarScan, PcdThatCannotBeRead) {
  Fixture f;
  const std::string p = temp("bad.pcd");
  std::ofstream(p) << "FIELDS x y\nSIZE 4 4\nTYPE F F\nPOINTS 1\nDATA ascii\n1 2\n";
  Status s = f.reader->read(p.c_str(), f.region, f.cloud.get());
  ASSERT_FALSE(s);
  EXPECT_NE(std::strstr(s.error().message(), "x, y and z"), nullptr) << s.error().message();
  std::ofstream(p) << "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA binary_compressed\n";
  s = f.reader->read(p.c_str(), f.region, f.cloud.get());
  ASSERT_FALSE(s);
  EXPECT_NE(std::strstr(s.error().message(), "binary_compressed"), nullptr);
  std::ofstream(p) << "FIELDS x y z\nSIZE 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n";
  s = f.reader->read(p.c_str(), f.region, f.cloud.get());
  ASSERT_FALSE(s);
  EXPECT_NE(std::strstr(s.error().message(), "inconsistent"), nullptr);
  const std::string other = temp("scan.las");
  std::ofstream(other) << "x";
  s = f.reader->read(other.c_str(), f.region, f.cloud.get());
  ASSERT_FALSE(s);
  EXPECT_NE(std::strstr(s.error().message(), "neither .bin"), nullptr);
  EXPECT_FALSE(f.reader->read("/nonexistent/scan.bin", f.region, f.cloud.get()));
}

// The hostile files of docs/hostile_input.md, each refused with its reason
// (they crashed, read garbage or hung before): an overflowing COUNT, a
// binary PCD whose header claims more than the file holds, more than 16
// fields, a scan that is /dev/zero or a FIFO.
Status read_pcd(Fixture& f, const std::string& text) {
  const std::string p = temp("hostile.pcd");
  std::ofstream(p, std::ios::binary) << text;
  return f.reader->read(p.c_str(), f.region, f.cloud.get());
}

void expect_refused(const Status& s, const char* why) {
  ASSERT_FALSE(s) << why;
  EXPECT_NE(std::strstr(s.error().message(), why), nullptr) << s.error().message();
}

TEST(LidarScan, HostileFilesAreRefusedWithTheirReason) {
  Fixture f;
  // 111 bytes: 4 * 2147483645 overflowed an int (a crash, UBSan: signed overflow).
  expect_refused(read_pcd(f,
                          "FIELDS x y z i\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 2147483645 1\n"
                          "POINTS 1\nDATA binary\n0123456789abcdef"),
                 "not a whole number in range");
  // Read garbage and "succeeded" before.
  expect_refused(read_pcd(f,
                          "FIELDS x y z i\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1000\n"
                          "POINTS 5\nDATA binary\n0123456789abcdef"),
                 "the file holds");
  std::string fields = "FIELDS x y z", sizes = "SIZE 4 4 4", types = "TYPE F F F";
  for (int i = 0; i < 14; ++i) fields += " a", sizes += " 4", types += " F";
  expect_refused(read_pcd(f, fields + "\n" + sizes + "\n" + types + "\nPOINTS 0\nDATA ascii\n"),
                 "more than 16 fields");
  expect_refused(read_pcd(f, "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1x\nDATA ascii\n"),
                 "not a whole number");
  // A KITTI scan that is a character device (read forever before).
  const std::string zero = temp("zero.bin");
  std::remove(zero.c_str());
  ASSERT_EQ(symlink("/dev/zero", zero.c_str()), 0);
  expect_refused(f.reader->read(zero.c_str(), f.region, f.cloud.get()), "a character device");
  const std::string fifo = temp("fifo.bin");
  std::remove(fifo.c_str());
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  expect_refused(f.reader->read(fifo.c_str(), f.region, f.cloud.get()), "a FIFO");
}

TEST(LidarSequence, ReadsPosesAndScansAndNamesBadOnes) {
  const std::string dir = temp("/lidar_seq");
  std::filesystem::create_directories(dir + "/lidar");
  const float pts[] = {1, 2, 3, 0, 4, 5, 6, 1};
  write_bytes(dir + "/lidar/a.bin", pts, sizeof pts);
  write_bytes(dir + "/lidar/short.bin", pts, 10);  // not a whole point
  std::ofstream(dir + "/lidar_poses.txt") << "# name x y z qw qx qy qz\n"
                                          << "lidar/a.bin 1 2 1.9 2 0 0 0\n"
                                          << "lidar/short.bin 3 4 1.9 1 0 0 0\n"
                                          << "lidar/missing.bin 5 6 1.9 1 0 0 0\n";
  auto seq = LidarSequence::open(dir.c_str());
  ASSERT_TRUE(seq) << seq.error().message();
  LidarSequence& s = **seq;
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s.entry(0).position[1], 2.0);
  EXPECT_EQ(s.entry(0).orientation[0], 1.0);  // normalised
  auto cloud = PointCloud::create(16);
  ASSERT_TRUE(cloud);
  ASSERT_TRUE(s.read(0, PointRegion{}, cloud->get()));
  EXPECT_EQ((*cloud)->size(), 2u);
  auto bad = s.read(1, PointRegion{}, cloud->get());
  ASSERT_FALSE(bad);
  EXPECT_NE(std::strstr(bad.error().message(), "short.bin"), nullptr) << bad.error().message();
  auto gone = s.read(2, PointRegion{}, cloud->get());
  ASSERT_FALSE(gone);
  EXPECT_NE(std::strstr(gone.error().message(), "missing.bin"), nullptr);
  EXPECT_FALSE(s.read(3, PointRegion{}, cloud->get()));

  std::ofstream(dir + "/lidar_poses.txt") << "lidar/a.bin 1 2 nope 1 0 0 0\n";
  auto malformed = LidarSequence::open(dir.c_str());
  ASSERT_FALSE(malformed);
  EXPECT_NE(std::strstr(malformed.error().message(), "lidar_poses.txt:1"), nullptr)
      << malformed.error().message();
  auto none = LidarSequence::open(temp("/no_such_sequence").c_str());
  ASSERT_FALSE(none);
  EXPECT_NE(std::strstr(none.error().message(), "lidar_poses.txt"), nullptr);
}

}  // namespace
}  // namespace aprt
