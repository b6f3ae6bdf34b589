// Camera frames to the network input: every ISA's kernel against the
// reference on every pixel format, odd sizes and random normalisation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "kernels/preprocess/preprocess_image.h"
#include "kernels/preprocess/u8_f32_preprocess__ref.h"
#include "tests/kernels/kernel_test_support.h"

namespace aprt::kernels {
namespace {

using namespace aprt::kernels::testing;

class PreprocessKernels : public F32KernelTest {};

// Camera frame -> network input: every pixel format, odd frame and output
// sizes (down- and upscaling, one output pixel, a partial vector), one and
// three channels, padded strides, random normalisation.
TEST_P(PreprocessKernels, PreprocessEveryFormat) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> mean(0.2f, 0.6f), std_(0.1f, 0.5f);
  const PixelFormat formats[] = {PixelFormat::kRgb24, PixelFormat::kBgr24, PixelFormat::kYuyv,
                                 PixelFormat::kUyvy,  PixelFormat::kNv12,  PixelFormat::kGray8};
  struct Geometry {
    int w, h, size, channels;
  };
  const Geometry geometries[] = {{37, 29, 17, 3},  {29, 37, 5, 3}, {640, 480, 64, 3},
                                 {101, 67, 33, 1}, {3, 3, 1, 3},   {131, 75, 224, 3},
                                 {64, 64, 64, 3},  {1, 1, 7, 3},   {250, 130, 129, 1}};
  auto plan = std::make_unique<PreprocessPlan>();
  for (PixelFormat f : formats) {
    for (const Geometry& g : geometries) {
      size_t stride = min_stride(f, g.w) + rng() % 7;
      if (f == PixelFormat::kNv12) stride = std::max(stride, size_t((g.w + 1) / 2) * 2);
      std::vector<uint8_t> frame(stride * size_t(g.h + (g.h + 1) / 2) + 16);
      for (uint8_t& b : frame) b = uint8_t(rng());
      PreprocessParams p{
          g.size, g.channels, {mean(rng), mean(rng), mean(rng)}, {std_(rng), std_(rng), std_(rng)}};
      const ImageView img{frame.data(), f, g.w, g.h, stride};
      const size_t n = size_t(g.size) * g.size * g.channels;
      std::vector<float> got(n + 8, -7.0f), want(n);
      ASSERT_TRUE(plan_preprocess(p, f, g.w, g.h, plan.get(), ks_->preprocess));
      preprocess_image(*plan, img, got.data());
      u8_f32_preprocess__ref(img, p, want.data());
      const std::string where = std::string(pixel_format_name(f)) + " " + std::to_string(g.w) +
                                "x" + std::to_string(g.h) + " -> " + std::to_string(g.size) + " c" +
                                std::to_string(g.channels);
      for (size_t i = 0; i < n; ++i) {
        ASSERT_NEAR(got[i], want[i], 1e-5f * std::max(1.0f, std::fabs(want[i])))
            << where << " at " << i;
      }
      for (size_t i = n; i < n + 8; ++i)
        ASSERT_EQ(got[i], -7.0f) << where << ": wrote past the end";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Isa, PreprocessKernels, ::testing::ValuesIn(f32_cases()),
                         case_name<F32Case>);

}  // namespace
}  // namespace aprt::kernels
