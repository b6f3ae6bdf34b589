// What `aprt eval` measures of a model on a labelled sequence: errors of
// every frame, of the frames the validity gate lets out (runtime/pose/
// pose_gate.h, as `aprt run` applies it), availability, and whether the
// published confidence covers the errors (FORMAT.md 1.3).
#pragma once

#include <cstddef>
#include <cstdio>
#include <vector>

#include "runtime/engine/pose_decode.h"

namespace aprt::cli {

struct ErrorStats {
  size_t n = 0;
  double median = 0, mean = 0, p90 = 0, p99 = 0, max = 0;
  double over_10 = 0, over_50 = 0;  // shares of frames beyond 10 and 50 (m or deg)
};

ErrorStats error_stats(std::vector<double> v);

// One frame as eval saw it.
struct EvalSample {
  double t_s = 0;  // the sequence's clock (frame index / rate)
  double position_error_m = 0, orientation_error_deg = 0;  // the model's estimate
  // The pose that goes out: the pose filter's where it runs, else the estimate.
  double published_position_error_m = 0, published_orientation_error_deg = 0;
  bool valid = false;  // no flag at all: what `aprt run` would publish as valid
  bool has_sigma = false;
  bool inside_position = false, inside_yaw = false;  // within the published 95 % regions
};

struct EvalSummary {
  size_t frames = 0, flagged_by_model = 0;
  ErrorStats position, orientation;                      // the model's, every frame
  bool filtered = false;                                 // the pose filter ran (sanity.filter)
  ErrorStats published_position, published_orientation;  // what goes out, every frame
  ErrorStats valid_position, valid_orientation;          // what goes out valid
  size_t valid = 0, valid_over_10m = 0, valid_over_10deg = 0;
  double first_valid_s = -1;  // after the first frame; -1: none
  size_t with_sigma = 0, inside_position = 0, inside_yaw = 0;
};

EvalSummary summarise(const std::vector<EvalSample>& samples, size_t flagged_by_model,
                      bool filtered = false);

// Whether the truth lies within the pose's published 95 % regions: the
// horizontal ellipse (chi^2 with 2 degrees of freedom) and the yaw interval.
void coverage_of(const PoseEstimate& p, const double truth_position[3],
                 const double truth_orientation[4], bool* inside_position, bool* inside_yaw);

void print_summary(const EvalSummary& s, FILE* out);
void print_summary_json(const EvalSummary& s, FILE* out);

}  // namespace aprt::cli
