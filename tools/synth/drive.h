// Driven trajectories through the town: lane-following routes over the street
// graph (right-hand traffic, the roundabout taken counter-clockwise), sampled
// at a fixed spacing.
#pragma once

#include <cstdint>
#include <vector>

#include "tools/synth/town.h"

namespace aprt::synth {

struct VehiclePose {
  double x, y, yaw;  // base_link on the ground; yaw from +x (east), counter-clockwise
};

struct RouteOptions {
  uint32_t seed = 1;
  bool cover_all = true;     // visit every street in both directions (training loops)
  double max_length = 1e9;   // metres
  double spacing = 1.0;      // metres between samples
  double lane_jitter = 0.4;  // slow lateral weaving within the lane, metres
  double yaw_jitter_deg = 2.0;
};

std::vector<VehiclePose> drive(const Town& town, const RouteOptions& options);

}  // namespace aprt::synth
