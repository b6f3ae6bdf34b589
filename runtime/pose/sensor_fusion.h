// Two sensors' base_link poses -- the run's own (a camera, or cameras already
// fused) and a companion sensor's with its own model (a LiDAR) -- combined
// into the one pose the outputs publish (docs/configuration.md, "A second
// sensor").
//
// Each sensor's estimate has already passed its own validity gate
// (pose_gate.h, with that sensor's limits): flags 0 means it may go out. The
// combination trusts that verdict and adds what only two sensors can tell:
//   - one valid: that one goes out, whichever sensor it is (the camera at
//     night, the LiDAR in a featureless tunnel: the other carries the run);
//   - both valid and agreeing (within the fusion's spreads): their
//     inverse-variance mean per axis for the position, the yaw interpolated
//     by the same weights, and the smaller variance that follows;
//   - both valid and disagreeing: one of them is wrong. The one whose gate
//     has passed its poses without a break for longer goes out -- a sensor is
//     weighed by its own validity history, not only by its stated variance,
//     because a model is confidently wrong now and then -- if that lead is at
//     least min_lead_s; otherwise neither (kPoseNoQuorum);
//   - with cross_check, one valid estimate that disagrees with the other
//     sensor's present (not valid, but finite and in bounds) estimate goes out
//     only with a valid history of min_lead_s; off by default: on the town's
//     nine validation drives it cost ~8 points of availability for no clear
//     gain in wrong valid poses (docs/evaluation.md, "Both sensors");
//   - neither valid: the estimate with the smaller stated horizontal variance
//     goes out with its own flags (withheld either way; what the console and
//     the errors show).
// Pure, fixed-size, allocation-free (@rt).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>

namespace aprt {

// One sensor's estimate of base_link in the map frame, with its variances
// (the model's calibrated sigma squared, or the model's validation error).
struct SensorEstimate {
  bool present = false;  // an estimate recent enough for this cycle
  uint32_t flags = 0;    // its own flags after its own gate; 0 = valid
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  double var_position[3] = {1, 1, 1};  // m^2, map axes
  double var_yaw = 1;                  // rad^2
  double valid_for_s = 0;              // how long its gate has passed its poses without a break
  bool usable() const { return present && flags == 0; }
};

struct SensorFusionParams {
  double max_position_spread_m = 5.0;  // two valid estimates farther apart disagree ...
  double max_yaw_spread_rad = 10.0 * 3.14159265358979323846 / 180.0;  // ... or this far in yaw
  double min_lead_s = 1.0;  // a disagreement goes to the longer valid history by at least this
  // One valid estimate that disagrees with the other sensor's present one
  // (not valid, but a real estimate: finite, in bounds) goes out only when its
  // own valid history is at least min_lead_s long.
  bool cross_check = false;
};

// Whose estimate a fused pose is.
enum class FusedFrom : uint8_t { kNone = 0, kPrimary = 1, kCompanion = 2, kBoth = 3 };
const char* fused_from_name(FusedFrom f);

struct SensorFusionResult {
  SensorEstimate pose;  // what goes out (flags 0: valid; else withheld, shown flagged)
  FusedFrom from = FusedFrom::kNone;  // whose estimate it is (kPrimary: exactly a)
  bool disagree = false;              // both valid, farther apart than the spreads
  double distance_m = -1;             // horizontal distance between the two (-1: not both present)
  double yaw_diff_rad = -1;           // and their yaw difference
};

// a: the run's own sensor; b: the companion's. @rt.
SensorFusionResult fuse_sensors(const SensorEstimate& a, const SensorEstimate& b,
                                const SensorFusionParams& p) noexcept;

// How long a sensor's estimates have been valid without a break, on its own
// clock (seconds). @rt.
class ValidStreak {
 public:
  double update(bool valid, double t_s) noexcept {
    if (!valid) {
      running_ = false;
      return 0;
    }
    if (!running_) since_s_ = t_s;
    running_ = true;
    return t_s - since_s_;
  }

 private:
  bool running_ = false;
  double since_s_ = 0;
};

}  // namespace aprt
