// The labelled sequences `aprt eval` reads, one per modality: each fills the
// engine's input for frame i and names its ground truth.
#pragma once

#include <cstdio>
#include <memory>

#include "drivers/input/odometry.h"
#include "runtime/engine/engine.h"

namespace aprt::cli {

struct EvalFrame {
  const char* name = "";
  const double* position = nullptr;     // ground truth, map frame
  const double* orientation = nullptr;  // w x y z
};

class EvalInputs {
 public:
  virtual ~EvalInputs() = default;
  virtual size_t size() const = 0;
  // Fills the engine's input for frame i; false with a message in `why`
  // when the frame cannot be read (the caller skips it).
  virtual bool fill(size_t i, Engine& engine, EvalFrame* frame, const char** why) = 0;
  // Frame i's recorded time (times.txt, seconds), or -1 when the sequence has
  // none (LiDAR sequences never do).
  virtual double time_s(size_t) const { return -1.0; }
  // Frame i's odometry reading (the sequence's odometry.txt); invalid
  // without one or where it does not cover the frame.
  virtual bool has_odometry() const { return false; }
  virtual OdometryReading odometry(size_t) const { return {}; }

 protected:
  const char* keep_reason(const Error& e) {  // the message outlives the Error
    std::snprintf(why_, sizeof why_, "%s", e.message());
    return why_;
  }

 private:
  char why_[512] = {};
};

// A DeepLoc-layout camera sequence (poses.txt + images), preprocessed as the
// runtime does; or a LiDAR sequence (lidar_poses.txt + scans) through the
// point gate and the BEV kernel with the model's geometry. Null after printing
// the reason as "aprt eval: ...".
std::unique_ptr<EvalInputs> open_eval_inputs(const char* data, const Engine& engine);

}  // namespace aprt::cli
