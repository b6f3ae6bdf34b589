// The model's input from a frame: a camera image (centre crop, bilinear
// resize, colour conversion, normalisation; docs/preprocessing.md) or a LiDAR
// scan (BEV histogram, or crop + farthest-point sampling + features;
// docs/lidar.md), with the geometry and normalisation the model file carries
// and the kernels the engine chose at load -- the loop and `aprt eval` /
// `aprt infer` hand it frames and never pick a preprocessing kernel
// themselves.
//
// One per input channel (camera or LiDAR), made at start-up for the largest
// frame or scan it will see; write() allocates nothing. A model loaded later
// (a reload) can take its input from the same EngineInput when its input is
// the same (runtime/loop/model_loader.h, reload_compatible).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "kernels/preprocess/lidar_input.h"
#include "kernels/preprocess/preprocess_image.h"
#include "runtime/base/expected.h"
#include "runtime/base/image.h"
#include "runtime/base/lidar_point.h"
#include "runtime/engine/engine.h"

namespace aprt {

// What a scan gave: points left after a points model's crop, and whether
// there were enough for the model.
using ScanInputResult = kernels::LidarInputResult;

class EngineInput {
 public:
  // Camera frames of this geometry for an image model. The message says why a
  // geometry cannot be mapped.
  static Expected<std::unique_ptr<EngineInput>> for_images(const Engine& engine, PixelFormat format,
                                                           int width, int height);
  // LiDAR scans of at most max_points points for a BEV or points model.
  static Expected<std::unique_ptr<EngineInput>> for_scans(const Engine& engine, size_t max_points);

  // @rt: re-plans in place when a camera renegotiated its geometry or format;
  // false if the new one cannot be mapped to the input (the frame is skipped).
  bool fit(PixelFormat format, int width, int height) noexcept;
  // @rt: the image (of the geometry fit() last accepted) into engine's input.
  void write_image(const ImageView& img, Engine& engine) const noexcept;
  // @rt: n points into engine's input (n at most max_points).
  ScanInputResult write_scan(const LidarPoint* points, size_t n, Engine& engine) noexcept;

  bool scans() const { return scans_; }

 private:
  EngineInput() = default;
  bool scans_ = false;
  bool points_model_ = false;
  bool fast_ = false;  // the engine runs fast kernels (the LiDAR sampler follows)
  std::unique_ptr<kernels::PreprocessPlan> plan_;
  kernels::BevInputParams bev_{};
  kernels::PointsInputParams points_{};
  std::vector<uint16_t> bev_counts_;
  std::vector<float> points_scratch_;
  size_t max_points_ = 0;
};

// The preprocessing kernels' parameters from a model's metadata.
kernels::PreprocessParams preprocess_params(const ModelMeta& m);
kernels::BevInputParams bev_input_params(const ModelMeta& m);
kernels::PointsInputParams points_input_params(const ModelMeta& m);

}  // namespace aprt
