// sensor_msgs/msg/PointCloud2 decoding (drivers/input/pointcloud2/pointcloud2_decode.*):
// any point_step and field layout, float64 coordinates, other intensity
// types, big-endian clouds, row padding; malformed messages refused whole
// with their reason; NaN and overflow through the point gate; no allocation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "drivers/input/pointcloud2/pointcloud2_decode.h"
#include "runtime/base/allocation_counter.h"

namespace aprt {
namespace {

struct Cloud {
  std::vector<PointFieldView> fields;
  std::vector<uint8_t> data;
  uint32_t height = 1, width = 0, point_step = 0, row_step = 0;
  bool big = false;
  PointCloud2View view() const {
    return {height,     width,    fields.data(), fields.size(), big,
            point_step, row_step, data.data(),   data.size()};
  }
};

template <class T>
void put(std::vector<uint8_t>& d, size_t at, T v, bool big = false) {
  uint8_t b[sizeof(T)];
  std::memcpy(b, &v, sizeof v);
  for (size_t i = 0; i < sizeof v; ++i) d[at + i] = big ? b[sizeof v - 1 - i] : b[i];
}

std::unique_ptr<PointCloud> cloud(size_t capacity = 64) {
  return std::move(PointCloud::create(capacity).value());
}

// A Velodyne-like layout: x y z intensity float32, ring uint16, time float32,
// 32-byte points, rows padded by 8 bytes.
Cloud velodyne_like(uint32_t rows, uint32_t cols) {
  Cloud c;
  c.fields = {{"x", 0, 7, 1},     {"y", 4, 7, 1},          {"z", 8, 7, 1},
              {"ring", 20, 4, 1}, {"intensity", 12, 7, 1}, {"time", 24, 7, 1}};
  c.height = rows;
  c.width = cols;
  c.point_step = 32;
  c.row_step = cols * 32 + 8;
  c.data.assign(size_t(c.row_step) * rows, 0xCD);
  for (uint32_t r = 0; r < rows; ++r) {
    for (uint32_t k = 0; k < cols; ++k) {
      const size_t at = size_t(r) * c.row_step + size_t(k) * 32;
      put<float>(c.data, at, float(r * 10 + k));
      put<float>(c.data, at + 4, -float(k));
      put<float>(c.data, at + 8, 0.5f * float(r));
      put<float>(c.data, at + 12, 7.0f);
      put<uint16_t>(c.data, at + 20, uint16_t(r));
    }
  }
  return c;
}

TEST(PointCloud2, DecodesAnyLayoutWithRowPadding) {
  const Cloud c = velodyne_like(3, 5);
  auto pc = cloud();
  CloudRefusal why;
  ASSERT_TRUE(decode_pointcloud2(c.view(), PointRegion{}, pc.get(), &why));
  EXPECT_EQ(why, CloudRefusal::kNone);
  ASSERT_EQ(pc->size(), 15u);
  const Point& p = pc->points()[2 * 5 + 3];
  EXPECT_EQ(p.x, 23.0f);
  EXPECT_EQ(p.y, -3.0f);
  EXPECT_EQ(p.z, 1.0f);
  EXPECT_EQ(p.intensity, 7.0f);
}

TEST(PointCloud2, Float64CoordinatesUint16IntensityAndBigEndian) {
  for (bool big : {false, true}) {
    Cloud c;
    c.fields = {{"intensity", 24, 4, 1}, {"z", 16, 8, 1}, {"y", 8, 8, 1}, {"x", 0, 8, 1}};
    c.width = 2;
    c.point_step = 26;
    c.row_step = 52;
    c.big = big;
    c.data.assign(52, 0);
    for (int k = 0; k < 2; ++k) {
      put<double>(c.data, 26 * k, 1.25 + k, big);
      put<double>(c.data, 26 * k + 8, -2.5, big);
      put<double>(c.data, 26 * k + 16, 0.75, big);
      put<uint16_t>(c.data, 26 * k + 24, uint16_t(300 + k), big);
    }
    auto pc = cloud();
    CloudRefusal why;
    ASSERT_TRUE(decode_pointcloud2(c.view(), PointRegion{}, pc.get(), &why)) << big;
    ASSERT_EQ(pc->size(), 2u);
    EXPECT_EQ(pc->points()[1].x, 2.25f);
    EXPECT_EQ(pc->points()[1].y, -2.5f);
    EXPECT_EQ(pc->points()[1].z, 0.75f);
    EXPECT_EQ(pc->points()[1].intensity, 301.0f);
  }
}

TEST(PointCloud2, NanOverflowAndEmptyGoThroughTheGate) {
  Cloud c = velodyne_like(1, 6);
  put<float>(c.data, 32 * 1, NAN);
  put<float>(c.data, 32 * 2 + 8, INFINITY);
  put<float>(c.data, 32 * 3, 1e9f);
  auto pc = cloud(2);
  CloudRefusal why;
  ASSERT_TRUE(decode_pointcloud2(c.view(), PointRegion{}, pc.get(), &why));
  EXPECT_EQ(pc->stats().read, 6u);
  EXPECT_EQ(pc->stats().non_finite, 2u);
  EXPECT_EQ(pc->size(), 2u);
  EXPECT_EQ(pc->stats().over_capacity, 2u);
  EXPECT_EQ(pc->stats().clipped, 1u);
  Cloud empty = velodyne_like(0, 0);
  empty.row_step = 0;
  ASSERT_TRUE(decode_pointcloud2(empty.view(), PointRegion{}, pc.get(), &why));
  EXPECT_EQ(pc->size(), 0u);
}

struct Bad {
  const char* what;
  void (*edit)(Cloud&);
  CloudRefusal reason;
  const char* message;
};

TEST(PointCloud2, MalformedMessagesAreRefusedWhole) {
  const Bad cases[] = {
      {"no z", [](Cloud& c) { c.fields.erase(c.fields.begin() + 2); }, CloudRefusal::kMissingField,
       "no 'z' field"},
      {"x as int16", [](Cloud& c) { c.fields[0].datatype = 3; }, CloudRefusal::kBadField,
       "coordinates must be FLOAT32 or FLOAT64"},
      {"unknown type", [](Cloud& c) { c.fields[4].datatype = 42; }, CloudRefusal::kBadField,
       "unknown datatype 42"},
      {"field outside the point", [](Cloud& c) { c.fields[2].offset = 30; },
       CloudRefusal::kBadField, "does not fit a 32-byte point"},
      {"count 0", [](Cloud& c) { c.fields[1].count = 0; }, CloudRefusal::kBadField, "count 0"},
      {"point_step 0", [](Cloud& c) { c.point_step = 0; }, CloudRefusal::kBadField,
       "does not fit a 0-byte point"},
      {"row too short", [](Cloud& c) { c.row_step = 100; }, CloudRefusal::kBadLayout,
       "row_step 100"},
      {"data short", [](Cloud& c) { c.data.resize(c.data.size() - 1); },
       CloudRefusal::kSizeMismatch, "needs"},
      {"data long", [](Cloud& c) { c.data.resize(c.data.size() + 4); }, CloudRefusal::kSizeMismatch,
       "needs"},
      {"height lies", [](Cloud& c) { c.height = 4000000000u; }, CloudRefusal::kSizeMismatch,
       "needs"},
  };
  for (const Bad& b : cases) {
    Cloud c = velodyne_like(2, 4);
    b.edit(c);
    auto pc = cloud();
    CloudRefusal why;
    ASSERT_TRUE(decode_pointcloud2(velodyne_like(1, 3).view(), PointRegion{}, pc.get(), &why));
    auto st = decode_pointcloud2(c.view(), PointRegion{}, pc.get(), &why);
    ASSERT_FALSE(st) << b.what;
    EXPECT_EQ(why, b.reason) << b.what;
    EXPECT_NE(std::strstr(st.error().message(), b.message), nullptr)
        << b.what << ": " << st.error().message();
    EXPECT_EQ(pc->size(), 3u) << b.what << ": the last good scan must survive";
  }
}

TEST(PointCloud2, DecodingAllocatesNothing) {
  const Cloud c = velodyne_like(16, 64);
  auto pc = cloud(2048);
  CloudRefusal why;
  Cloud bad = c;  // x missing: the refusal's message is formatted in place
  bad.fields.erase(bad.fields.begin());
  const AllocationScope scope;
  for (int i = 0; i < 10; ++i)
    ASSERT_TRUE(decode_pointcloud2(c.view(), PointRegion{}, pc.get(), &why));
  EXPECT_FALSE(decode_pointcloud2(bad.view(), PointRegion{}, pc.get(), &why));
  EXPECT_EQ(scope.count(), 0u);
}

}  // namespace
}  // namespace aprt
