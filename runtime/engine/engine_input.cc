#include "runtime/engine/engine_input.h"

#include <new>

#include "runtime/base/check.h"

namespace aprt {

kernels::PreprocessParams preprocess_params(const ModelMeta& m) {
  kernels::PreprocessParams pp{int(m.input_shape[1]), int(m.input_shape[3]), {}, {}};
  for (int c = 0; c < m.norm_channels && c < 3; ++c) {
    pp.mean[c] = m.norm_mean[c];
    pp.std[c] = m.norm_std[c];
  }
  return pp;
}

kernels::BevInputParams bev_input_params(const ModelMeta& m) {
  kernels::BevInputParams p{{int(m.input_shape[1]), m.bev_cell_m, m.bev_x_min, m.bev_y_min,
                             m.bev_height_threshold_m, m.bev_clip_count},
                            {0, 0},
                            {1, 1}};
  for (int c = 0; c < 2 && c < m.norm_channels; ++c) {
    p.mean[c] = m.norm_mean[c];
    p.std[c] = m.norm_std[c];
  }
  return p;
}

kernels::PointsInputParams points_input_params(const ModelMeta& m) {
  kernels::PointsInputParams p{
      int(m.input_shape[1]), m.points_crop_radius_m, m.points_coord_scale_m, {}, {}};
  for (int c = 0; c < 6; ++c) {
    p.mean[c] = c < m.norm_channels ? m.norm_mean[c] : 0.0f;
    p.std[c] = c < m.norm_channels ? m.norm_std[c] : 1.0f;
  }
  return p;
}

Expected<std::unique_ptr<EngineInput>> EngineInput::for_images(const Engine& engine,
                                                               PixelFormat format, int width,
                                                               int height) {
  const ModelMeta& m = engine.meta();
  APRT_ENSURE(m.modality == format::Modality::kImage, Errc::kWrongTarget,
              "input: a %s model takes LiDAR scans, not camera frames",
              format::modality_name(m.modality));
  std::unique_ptr<EngineInput> in(new (std::nothrow) EngineInput());
  APRT_ENSURE(in != nullptr, Errc::kOutOfMemory, "input: out of memory");
  in->plan_.reset(new (std::nothrow) kernels::PreprocessPlan());
  APRT_ENSURE(in->plan_ != nullptr, Errc::kOutOfMemory, "input: out of memory");
  const kernels::PreprocessParams pp = preprocess_params(m);
  const kernels::KernelSet* ks = engine.kernel_set();
  APRT_ENSURE(kernels::plan_preprocess(pp, format, width, height, in->plan_.get(),
                                       ks ? ks->preprocess : nullptr),
              Errc::kInvalidArgument,
              "input: cannot map %dx%d %s frames to the model's %dx%d input", width, height,
              pixel_format_name(format), pp.size, pp.size);
  return in;
}

Expected<std::unique_ptr<EngineInput>> EngineInput::for_scans(const Engine& engine,
                                                              size_t max_points) {
  const ModelMeta& m = engine.meta();
  APRT_ENSURE(m.modality != format::Modality::kImage, Errc::kWrongTarget,
              "input: an image model takes camera frames, not LiDAR scans");
  std::unique_ptr<EngineInput> in(new (std::nothrow) EngineInput());
  APRT_ENSURE(in != nullptr, Errc::kOutOfMemory, "input: out of memory");
  in->scans_ = true;
  in->max_points_ = max_points;
  in->fast_ = engine.kernel_set() != nullptr;
  in->points_model_ = m.modality == format::Modality::kLidarPoints;
  if (in->points_model_) {
    in->points_ = points_input_params(m);
    in->points_scratch_.resize(
        kernels::lidar_points_input_scratch(max_points, in->points_.samples));
  } else {
    in->bev_ = bev_input_params(m);
    in->bev_counts_.resize(size_t(in->bev_.bev.grid) * in->bev_.bev.grid * 2);
  }
  return in;
}

bool EngineInput::fit(PixelFormat format, int width, int height) noexcept {
  kernels::PreprocessPlan& p = *plan_;
  if (width == p.width && height == p.height && format == p.format) return true;
  return kernels::plan_preprocess(p.params, format, width, height, &p);
}

void EngineInput::write_image(const ImageView& img, Engine& engine) const noexcept {
  kernels::preprocess_image(*plan_, img, engine.input().f32());
}

ScanInputResult EngineInput::write_scan(const LidarPoint* points, size_t n,
                                        Engine& engine) noexcept {
  if (n > max_points_) n = max_points_;
  if (points_model_) {
    return kernels::lidar_points_input(points_, points, n, fast_, points_scratch_.data(),
                                       engine.input().f32());
  }
  return kernels::lidar_bev_input(bev_, points, n, bev_counts_.data(), engine.input().f32());
}

}  // namespace aprt
