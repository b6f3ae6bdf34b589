#include "runtime/cli/eval_inputs.h"

#include <cstdio>
#include <vector>

#include "drivers/input/frame.h"
#include "drivers/input/lidar/lidar_sequence.h"
#include "drivers/input/replay/deeploc_replay.h"
#include "runtime/engine/engine_input.h"

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
    auto input = EngineInput::for_images(e, PixelFormat::kRgb24, r.width(), r.height());
    if (!input) {
      std::fprintf(stderr, "aprt eval: %s\n", input.error().message());
      return nullptr;
    }
    in->input_ = std::move(input.value());
    in->pixels_.resize(r.frame_bytes());
    in->frame_.data = in->pixels_.data();
    in->frame_.capacity = in->pixels_.size();
    return in;
  }
  size_t size() const override { return replay_->size(); }
  double time_s(size_t i) const override {
    return replay_->has_times() ? replay_->entry(i).time_s : -1.0;
  }
  bool has_odometry() const override { return replay_->has_odometry(); }
  OdometryReading odometry(size_t i) const override { return replay_->reading(i); }
  bool fill(size_t i, Engine& e, EvalFrame* f, const char** why) override {
    if (Status s = replay_->read(i, &frame_, i, 0); !s) {
      *why = keep_reason(s.error());
      return false;
    }
    input_->write_image(frame_.view(), e);
    f->name = frame_.info.name;
    f->position = frame_.info.truth_position;
    f->orientation = frame_.info.truth_orientation;
    return true;
  }

 private:
  std::unique_ptr<DeeplocReplay> replay_;
  std::unique_ptr<EngineInput> input_;
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
    auto input = EngineInput::for_scans(e, kMaxPoints);
    if (!input) {
      std::fprintf(stderr, "aprt eval: %s\n", input.error().message());
      return nullptr;
    }
    in->input_ = std::move(input.value());
    return in;
  }
  size_t size() const override { return seq_->size(); }
  bool fill(size_t i, Engine& e, EvalFrame* f, const char** why) override {
    if (Status s = seq_->read(i, PointRegion{}, cloud_.get()); !s) {
      *why = keep_reason(s.error());
      return false;
    }
    input_->write_scan(cloud_->points(), cloud_->size(), e);
    const ReplayEntry& en = seq_->entry(i);
    f->name = en.name;
    f->position = en.position;
    f->orientation = en.orientation;
    return true;
  }

 private:
  std::unique_ptr<LidarSequence> seq_;
  std::unique_ptr<PointCloud> cloud_;
  std::unique_ptr<EngineInput> input_;
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
