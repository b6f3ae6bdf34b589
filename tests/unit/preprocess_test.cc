// The runtime's preprocessing against the Python training transform, for every
// pixel format, and the table-driven kernel against the reference; LiDAR scans
// through the reader, the point gate and both BEV kernels against the BEV
// histogram the LiDAR model is trained with (aprt_tools/lidar_bev.py).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "drivers/codec/image_decoder.h"
#include "drivers/input/lidar/point_cloud.h"
#include "drivers/input/lidar/scan_reader.h"
#include "kernels/preprocess/lidar__ref.h"
#include "kernels/preprocess/lidar_fast.h"
#include "kernels/preprocess/lidar_input.h"
#include "kernels/preprocess/preprocess_image.h"
#include "kernels/preprocess/u8_f32_preprocess__ref.h"
#include "kernels/table/cpu_features.h"
#include "kernels/table/kernel_table.h"
#include "runtime/base/allocation_counter.h"
#include "tests/support/test_files.h"

namespace aprt {
namespace {

PixelFormat parse_format(const std::string& s) {
  if (s == "RGB24") return PixelFormat::kRgb24;
  if (s == "BGR24") return PixelFormat::kBgr24;
  if (s == "YUYV") return PixelFormat::kYuyv;
  if (s == "UYVY") return PixelFormat::kUyvy;
  if (s == "NV12") return PixelFormat::kNv12;
  return PixelFormat::kGray8;
}

kernels::PreprocessParams imagenet(int size) {
  return {size, 3, {0.485f, 0.456f, 0.406f}, {0.229f, 0.224f, 0.225f}};
}

TEST(Preprocess, MatchesTheTrainingTransformForEveryFormat) {
  const std::string dir = test::env_dir("APRT_PREPROCESS_DIR");
  if (dir.empty()) GTEST_SKIP() << "APRT_PREPROCESS_DIR not set";
  std::ifstream cases(dir + "/cases.txt");
  std::string line;
  int checked = 0;
  auto plan = std::make_unique<kernels::PreprocessPlan>();
  while (std::getline(cases, line)) {
    std::istringstream in(line);
    std::string name, fmt;
    int w, h, size;
    size_t stride;
    in >> name >> fmt >> w >> h >> stride >> size;
    const auto raw = test::read_bytes(dir + "/" + name + ".raw");
    const auto want = test::read_f32(dir + "/" + name + ".f32");
    const PixelFormat f = parse_format(fmt);
    ASSERT_EQ(raw.size(), frame_bytes(f, w, h)) << name;
    const ImageView img{raw.data(), f, w, h, stride};
    std::vector<float> got(want.size()), ref(want.size());
    ASSERT_TRUE(kernels::plan_preprocess(imagenet(size), f, w, h, plan.get())) << name;
    const AllocationScope allocs;
    kernels::preprocess_image(*plan, img, got.data());
    EXPECT_EQ(allocs.count(), 0u);
    kernels::u8_f32_preprocess__ref(img, imagenet(size), ref.data());
    for (size_t i = 0; i < want.size(); ++i) {
      ASSERT_NEAR(got[i], want[i], 2e-5) << name << " at " << i;
      ASSERT_EQ(got[i], ref[i]) << name << " at " << i;  // same arithmetic, bit for bit
    }
    // The ISA kernels this CPU runs, against the same Python transform.
    for (const kernels::IsaParts& p : kernels::isa_parts()) {
      if (!p.f32_runs) continue;
      const kernels::KernelSet* ks = p.f32;
      auto fast = std::make_unique<kernels::PreprocessPlan>();
      ASSERT_TRUE(kernels::plan_preprocess(imagenet(size), f, w, h, fast.get(), ks->preprocess));
      const AllocationScope fast_allocs;
      kernels::preprocess_image(*fast, img, got.data());
      EXPECT_EQ(fast_allocs.count(), 0u);
      for (size_t i = 0; i < want.size(); ++i) {
        ASSERT_NEAR(got[i], want[i], 2e-5) << name << " (" << ks->isa << ") at " << i;
      }
    }
    ++checked;
  }
  EXPECT_GE(checked, 15);
}

TEST(Preprocess, DecodedPngMatchesTheTrainingTransform) {
  const std::string dir = test::env_dir("APRT_PREPROCESS_DIR");
  if (dir.empty()) GTEST_SKIP() << "APRT_PREPROCESS_DIR not set";
  auto dec = ImageDecoder::create(1 << 20);
  if (!dec && dec.error().code() == Errc::kUnsupported) GTEST_SKIP() << dec.error().message();
  ASSERT_TRUE(dec) << dec.error().message();
  std::vector<uint8_t> rgb(52 * 30 * 3);
  auto img = (*dec)->decode((dir + "/rgb.png").c_str(), rgb.data(), rgb.size());
  ASSERT_TRUE(img) << img.error().message();
  ASSERT_EQ(img->width, 52);
  ASSERT_EQ(img->height, 30);
  const auto want = test::read_f32(dir + "/png.f32");
  std::vector<float> got(want.size());
  auto plan = std::make_unique<kernels::PreprocessPlan>();
  ASSERT_TRUE(kernels::plan_preprocess(imagenet(24), PixelFormat::kRgb24, 52, 30, plan.get()));
  kernels::preprocess_image(*plan, {rgb.data(), PixelFormat::kRgb24, 52, 30, 52 * 3}, got.data());
  for (size_t i = 0; i < want.size(); ++i) ASSERT_NEAR(got[i], want[i], 2e-5) << i;
}

TEST(Preprocess, BevHistogramMatchesTheTrainingTransform) {
  const std::string dir = test::env_dir("APRT_PREPROCESS_DIR");
  if (dir.empty()) GTEST_SKIP() << "APRT_PREPROCESS_DIR not set";
  std::ifstream cases(dir + "/bev.txt");
  ASSERT_TRUE(cases) << "bev.txt missing";
  auto reader = ScanReader::create();
  auto cloud = PointCloud::create(1 << 16);
  ASSERT_TRUE(reader && cloud);
  std::string line;
  int checked = 0;
  while (std::getline(cases, line)) {
    std::istringstream f(line);
    std::string name;
    kernels::BevParams b{};
    f >> name >> b.grid >> b.cell_m >> b.x_min >> b.y_min >> b.height_threshold_m >> b.clip_count;
    ASSERT_TRUE(f) << line;
    ASSERT_TRUE((*reader)->read((dir + "/" + name + ".bin").c_str(), PointRegion{}, cloud->get()));
    const auto want = test::read_f32(dir + "/" + name + ".f32");
    ASSERT_EQ(want.size(), size_t(b.grid) * b.grid * 2);
    std::vector<float> ref(want.size()), fast(want.size());
    std::vector<uint16_t> counts(want.size());
    const PointCloud& pc = **cloud;
    kernels::lidar_bev_histogram__ref(pc.points(), pc.size(), b, ref.data());
    kernels::lidar_bev_histogram(pc.points(), pc.size(), b, counts.data(), fast.data());
    for (size_t i = 0; i < want.size(); ++i) {
      ASSERT_EQ(ref[i], want[i]) << name << " cell " << i / 2 << " channel " << i % 2;
      ASSERT_EQ(fast[i], want[i]) << name << " cell " << i / 2 << " channel " << i % 2;
    }
    ++checked;
  }
  EXPECT_EQ(checked, 3);
}

TEST(Preprocess, PointsInputMatchesTheTrainingTransform) {
  const std::string dir = test::env_dir("APRT_PREPROCESS_DIR");
  if (dir.empty()) GTEST_SKIP() << "APRT_PREPROCESS_DIR not set";
  std::ifstream cases(dir + "/points.txt");
  ASSERT_TRUE(cases) << "points.txt missing";
  auto reader = ScanReader::create();
  auto cloud = PointCloud::create(1 << 16);
  ASSERT_TRUE(reader && cloud);
  std::string line;
  int checked = 0;
  while (std::getline(cases, line)) {
    std::istringstream f(line);
    std::string name;
    kernels::PointsInputParams p{0, 0, 0, {0, 0, 0, 0, 0, 0}, {1, 1, 1, 1, 1, 1}};
    int enough = 0;
    f >> name >> p.samples >> p.crop_radius_m >> p.coord_scale_m >> enough;
    ASSERT_TRUE(f) << line;
    // Through the runtime's reader and gate, as a replayed or live scan goes.
    ASSERT_TRUE((*reader)->read((dir + "/" + name + ".bin").c_str(), PointRegion{}, cloud->get()));
    const auto want = test::read_f32(dir + "/" + name + ".f32");
    ASSERT_EQ(want.size(), size_t(p.samples) * 6);
    const PointCloud& pc = **cloud;
    std::vector<float> scratch(kernels::lidar_points_input_scratch(pc.size(), p.samples));
    for (bool fast : {false, true}) {
      std::vector<float> got(want.size(), -1.0f);
      const auto r =
          kernels::lidar_points_input(p, pc.points(), pc.size(), fast, scratch.data(), got.data());
      EXPECT_EQ(r.enough, enough != 0) << name;
      for (size_t i = 0; i < want.size(); ++i) {
        // Coordinates are copies (exact); the mean is summed in double in a
        // different order than numpy's pairwise sum, a last-bit difference at most.
        ASSERT_NEAR(got[i], want[i], 1e-6f * (1.0f + std::fabs(want[i])))
            << name << " sample " << i / 6 << " feature " << i % 6 << (fast ? " fast" : " ref");
        if (i % 6 < 3) {
          ASSERT_EQ(got[i], want[i]) << name << " sample " << i / 6;
        }
      }
    }
    ++checked;
  }
  EXPECT_EQ(checked, 4);
}

TEST(Preprocess, DecoderRefusesCorruptFiles) {
  auto dec = ImageDecoder::create(1 << 20);
  if (!dec && dec.error().code() == Errc::kUnsupported) GTEST_SKIP() << dec.error().message();
  ASSERT_TRUE(dec);
  const std::string path = testing::TempDir() + "/corrupt.png";
  const std::string dir = test::env_dir("APRT_PREPROCESS_DIR");
  std::vector<uint8_t> png =
      dir.empty() ? std::vector<uint8_t>() : test::read_bytes(dir + "/rgb.png");
  if (png.empty()) GTEST_SKIP() << "APRT_PREPROCESS_DIR not set";
  png.resize(png.size() / 2);  // truncated
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(png.data()), long(png.size()));
  std::vector<uint8_t> out(52 * 30 * 3);
  auto r = (*dec)->decode(path.c_str(), out.data(), out.size());
  ASSERT_FALSE(r);
  EXPECT_NE(std::strstr(r.error().message(), "corrupt.png"), nullptr) << r.error().message();
  const std::string junk = testing::TempDir() + "/junk.png";
  std::ofstream(junk) << "not an image at all";
  auto j = (*dec)->decode(junk.c_str(), out.data(), out.size());
  ASSERT_FALSE(j);
  EXPECT_NE(std::strstr(j.error().message(), "neither PNG nor JPEG"), nullptr);
  auto missing = (*dec)->decode("/nonexistent/x.png", out.data(), out.size());
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code(), Errc::kIo);
}

TEST(Preprocess, PlanRefusesUnusableGeometry) {
  auto plan = std::make_unique<kernels::PreprocessPlan>();
  EXPECT_FALSE(kernels::plan_preprocess(imagenet(0), PixelFormat::kRgb24, 10, 10, plan.get()));
  EXPECT_FALSE(kernels::plan_preprocess(imagenet(600), PixelFormat::kRgb24, 10, 10, plan.get()));
  EXPECT_FALSE(kernels::plan_preprocess(imagenet(32), PixelFormat::kRgb24, 0, 10, plan.get()));
}

}  // namespace
}  // namespace aprt
