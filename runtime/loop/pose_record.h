// What the inference thread hands to the publishers for every frame it ran.
#pragma once

#include <cstdint>

#include "drivers/input/odometry.h"
#include "runtime/engine/pose_decode.h"
#include "runtime/pose/pose_flags.h"

namespace aprt {

enum class RunState : uint8_t { kStarting, kRunning, kDegraded, kFault, kStopping };
const char* run_state_name(RunState s);

// A fusion cycle as the diagnostics show it (multi-camera runs only).
struct FusionSummary {
  uint8_t cameras = 0;  // configured; 0 or 1: no fusion
  uint8_t present = 0, usable = 0, inliers = 0;
  uint8_t inlier_mask = 0;
  float deviation_m[8] = {}, deviation_deg[8] = {};  // NaN: no usable estimate
  float spread_m = 0, spread_deg = 0;
};

// The companion sensor's part in a pose (fusion.companion runs only).
struct CompanionNote {
  bool configured = false;
  bool present = false;   // an estimate recent enough for this cycle
  uint8_t from = 0;       // FusedFrom (runtime/pose/sensor_fusion.h): what went out
  bool disagree = false;  // both valid, apart
  uint32_t flags = 0;     // the companion estimate's own flags
  float distance_m = -1;  // between the two estimates (-1: not both present)
  float yaw_diff_deg = -1;
  float age_ms = -1;  // how much older the companion's frame is than this cycle's (-1: none)
};

// The pose filter's part in a pose (sanity.filter runs only).
struct FilterNote {
  bool configured = false;
  bool fix = false;
  uint8_t use = 0;        // PoseFilter::Use: what this frame's estimate did
  uint16_t refused = 0;   // estimates refused in a row
  float radius95_m = -1;  // the filter's 95 % horizontal radius (-1: no fix)
  float yaw95_deg = -1;   // and yaw half-interval
};

struct PoseRecord {
  uint64_t index = 0;           // n-th pose of this run
  uint64_t frame_sequence = 0;  // source frame counter
  uint32_t source = 0;
  int64_t capture_ns = 0;       // the frame's capture time: the pose's timestamp
  int64_t source_stamp_ns = 0;  // the sensor's own stamp (PointCloud2 header), if any: used instead
  int64_t inference_start_ns = 0;
  int64_t inference_end_ns = 0;
  PoseEstimate pose;  // the (trigger) sensor's pose in the training map frame: console, errors
  // base_link in the training map frame: what the outputs publish (after the
  // map offset). The extrinsic is applied once, by the estimator (where
  // several cameras are fused, this is the fused pose).
  double base_position[3] = {};
  double base_orientation[4] = {1, 0, 0, 0};
  uint32_t flags = 0;  // pose flags | loop flags; 0 = valid
  RunState state = RunState::kStarting;
  bool has_truth = false;
  double truth_position[3] = {};
  double truth_orientation[4] = {1, 0, 0, 0};
  char name[128] = {};
  // The frame's odometry reading (a source that knows it): the pose filter
  // (sanity.filter) carries its pose between frames with it.
  OdometryReading odometry;
  FusionSummary fusion;
  CompanionNote companion;
  FilterNote filter;
};

}  // namespace aprt
