#include "runtime/cli/eval_inputs.h"

#include <cstdio>
#include <vector>

#include "drivers/frame/frame.h"
#include "drivers/lidar/lidar_sequence.h"
#include "drivers/replay/deeploc_replay.h"
#include "kernels/preprocess/lidar_input.h"
#include "kernels/preprocess/preprocess_image.h"
#include "runtime/engine/model_input.h"

namespace aprt::cli {
namespace {

class CameraInputs final : public EvalInputs {
 public:
  static std::unique_ptr<EvalInputs> open(const char* data, const Engine& e) {
    auto replay = DeeplocReplay::open(data);
    if (!replay) {
      std::fprintf(stderr, "aprt eval: %s\n", replay.error().message());
      return nullptr;
    }
    std::unique_ptr<CameraInputs> in(new CameraInputs());
    in->replay_ = std::move(replay.value());
    DeeplocReplay& r = *in->replay_;
    const kernels::PreprocessParams pp = preprocess_params(e.meta());
    in->plan_ = std::make_unique<kernels::PreprocessPlan>();
    if (!kernels::plan_preprocess(pp, PixelFormat::kRgb24, r.width(), r.height(), in->plan_.get(),
                                  e.kernel_set() ? e.kernel_set()->preprocess : nullptr)) {
      std::fprintf(stderr, "aprt eval: cannot map %dx%d frames to the %dx%d input\n", r.width(),
                   r.height(), pp.size, pp.size);
      return nullptr;
    }
    in->pixels_.resize(r.frame_bytes());
    in->frame_.data = in->pixels_.data();
    in->frame_.capacity = in->pixels_.size();
    return in;
  }
  size_t size() const override { return replay_->size(); }
  bool fill(size_t i, float* input, EvalFrame* f, const char** why) override {
    if (Status s = replay_->read(i, &frame_, i, 0); !s) {
      *why = keep_reason(s.error());
      return false;
    }
    kernels::preprocess_image(*plan_, frame_.view(), input);
    f->name = frame_.info.name;
    f->position = frame_.info.truth_position;
    f->orientation = frame_.info.truth_orientation;
    return true;
  }

 private:
  std::unique_ptr<DeeplocReplay> replay_;
  std::unique_ptr<kernels::PreprocessPlan> plan_;
  std::vector<uint8_t> pixels_;
  FrameBuffer frame_;
};

// Scans of up to kMaxPoints points (more are dropped and counted by the
// gate), made into the model's input as the runtime does (BEV histogram or
// sampled points, kernels/preprocess/lidar_input.h), with the model's geometry.
class LidarInputs final : public EvalInputs {
 public:
  static constexpr size_t kMaxPoints = size_t(1) << 20;

  static std::unique_ptr<EvalInputs> open(const char* data, const Engine& e) {
    auto seq = LidarSequence::open(data);
    if (!seq) {
      std::fprintf(stderr, "aprt eval: %s\n", seq.error().message());
      return nullptr;
    }
    auto cloud = PointCloud::create(kMaxPoints);
    if (!cloud) {
      std::fprintf(stderr, "aprt eval: %s\n", cloud.error().message());
      return nullptr;
    }
    std::unique_ptr<LidarInputs> in(new LidarInputs());
    in->seq_ = std::move(seq.value());
    in->cloud_ = std::move(cloud.value());
    const ModelMeta& m = e.meta();
    in->points_model_ = m.modality == format::Modality::kLidarPoints;
    in->fast_ = e.kernel_set() != nullptr;
    if (in->points_model_) {
      in->points_ = points_input_params(m);
      in->scratch_.resize(kernels::lidar_points_input_scratch(kMaxPoints, in->points_.samples));
    } else {
      in->bev_ = bev_input_params(m);
      in->counts_.resize(size_t(in->bev_.bev.grid) * in->bev_.bev.grid * 2);
    }
    return in;
  }
  size_t size() const override { return seq_->size(); }
  bool fill(size_t i, float* input, EvalFrame* f, const char** why) override {
    if (Status s = seq_->read(i, PointRegion{}, cloud_.get()); !s) {
      *why = keep_reason(s.error());
      return false;
    }
    if (points_model_) {
      kernels::lidar_points_input(points_, cloud_->points(), cloud_->size(), fast_, scratch_.data(),
                                  input);
    } else {
      kernels::lidar_bev_input(bev_, cloud_->points(), cloud_->size(), counts_.data(), input);
    }
    const ReplayEntry& en = seq_->entry(i);
    f->name = en.name;
    f->position = en.position;
    f->orientation = en.orientation;
    return true;
  }

 private:
  std::unique_ptr<LidarSequence> seq_;
  std::unique_ptr<PointCloud> cloud_;
  bool points_model_ = false, fast_ = true;
  kernels::BevInputParams bev_{};
  kernels::PointsInputParams points_{};
  std::vector<uint16_t> counts_;
  std::vector<float> scratch_;
};

}  // namespace

std::unique_ptr<EvalInputs> open_eval_inputs(const char* data, const Engine& engine) {
  switch (engine.meta().modality) {
    case format::Modality::kImage: return CameraInputs::open(data, engine);
    case format::Modality::kLidarBev:
    case format::Modality::kLidarPoints: return LidarInputs::open(data, engine);
  }
  std::fprintf(stderr, "aprt eval: no evaluation for modality '%s'\n",
               format::modality_name(engine.meta().modality));
  return nullptr;
}

}  // namespace aprt::cli
