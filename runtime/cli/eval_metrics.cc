#include "runtime/cli/eval_metrics.h"

#include <algorithm>
#include <cmath>

#include "runtime/pose/pose_gate.h"

namespace aprt::cli {
namespace {

constexpr double kChi2_95 = 5.991464547107979;  // 2 degrees of freedom
constexpr double kZ95 = 1.959963984540054;

double share(size_t k, size_t n) {
  return n ? double(k) / double(n) : 0.0;
}

}  // namespace

ErrorStats error_stats(std::vector<double> v) {
  ErrorStats s;
  s.n = v.size();
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  double sum = 0;
  size_t o10 = 0, o50 = 0;
  for (double x : v) {
    sum += x;
    o10 += x > 10.0;
    o50 += x > 50.0;
  }
  auto q = [&](double p) {
    return v[std::min(v.size() - 1, size_t(p * double(v.size() - 1) + 0.5))];
  };
  s.median = q(0.5);
  s.mean = sum / double(v.size());
  s.p90 = q(0.9);
  s.p99 = q(0.99);
  s.max = v.back();
  s.over_10 = share(o10, v.size());
  s.over_50 = share(o50, v.size());
  return s;
}

void coverage_of(const PoseEstimate& p, const double truth_position[3],
                 const double truth_orientation[4], bool* inside_position, bool* inside_yaw) {
  const double ex = p.position[0] - truth_position[0], ey = p.position[1] - truth_position[1];
  const double sx = p.sigma_position_m[0], sy = p.sigma_position_m[1];
  *inside_position = (ex * ex) / (sx * sx) + (ey * ey) / (sy * sy) <= kChi2_95;
  const double dyaw = wrap_angle(quaternion_yaw(p.orientation) - quaternion_yaw(truth_orientation));
  *inside_yaw = std::fabs(dyaw) <= kZ95 * p.sigma_rotation_rad[2];
}

EvalSummary summarise(const std::vector<EvalSample>& samples, size_t flagged_by_model,
                      bool filtered) {
  EvalSummary s;
  s.frames = samples.size();
  s.flagged_by_model = flagged_by_model;
  s.filtered = filtered;
  std::vector<double> pe, oe, ppe, poe, vpe, voe;
  const double t0 = samples.empty() ? 0.0 : samples.front().t_s;
  for (const EvalSample& e : samples) {
    pe.push_back(e.position_error_m);
    oe.push_back(e.orientation_error_deg);
    ppe.push_back(e.published_position_error_m);
    poe.push_back(e.published_orientation_error_deg);
    if (e.valid) {
      vpe.push_back(e.published_position_error_m);
      voe.push_back(e.published_orientation_error_deg);
      s.valid_over_10m += e.published_position_error_m > 10.0;
      s.valid_over_10deg += e.published_orientation_error_deg > 10.0;
      if (s.first_valid_s < 0) s.first_valid_s = e.t_s - t0;
    }
    if (e.has_sigma) {
      ++s.with_sigma;
      s.inside_position += e.inside_position;
      s.inside_yaw += e.inside_yaw;
    }
  }
  s.valid = vpe.size();
  s.position = error_stats(pe);
  s.orientation = error_stats(oe);
  s.published_position = error_stats(ppe);
  s.published_orientation = error_stats(poe);
  s.valid_position = error_stats(vpe);
  s.valid_orientation = error_stats(voe);
  return s;
}

void print_summary(const EvalSummary& s, FILE* out) {
  const auto row = [&](const char* what, const ErrorStats& e, const char* unit) {
    std::fprintf(out,
                 "%-12s median %.2f %s  mean %.2f  p90 %.2f  p99 %.2f  max %.2f;  > 10: %.1f %%  "
                 "> 50: %.1f %%\n",
                 what, e.median, unit, e.mean, e.p90, e.p99, e.max, 100 * e.over_10,
                 100 * e.over_50);
  };
  row("position", s.position, "m");
  row("orientation", s.orientation, "deg");
  if (s.filtered) {
    std::fprintf(out, "published    the pose filter's pose (model and odometry), every frame:\n");
    row("  position", s.published_position, "m");
    row("  orientation", s.published_orientation, "deg");
  }
  std::fprintf(out,
               "valid        %zu of %zu frames (%.1f %%: availability), the first %s%.2f s after "
               "the start\n",
               s.valid, s.frames, 100 * share(s.valid, s.frames),
               s.first_valid_s < 0 ? "never, " : "", s.first_valid_s < 0 ? 0.0 : s.first_valid_s);
  if (s.valid) {
    row("  position", s.valid_position, "m");
    row("  orientation", s.valid_orientation, "deg");
    std::fprintf(out, "  wrong      %zu valid poses > 10 m off, %zu > 10 deg off\n",
                 s.valid_over_10m, s.valid_over_10deg);
  }
  if (s.with_sigma) {
    std::fprintf(out,
                 "confidence   the published 95 %% regions hold %.1f %% of the horizontal "
                 "position errors and %.1f %% of the yaw errors (%zu frames)\n",
                 100 * share(s.inside_position, s.with_sigma),
                 100 * share(s.inside_yaw, s.with_sigma), s.with_sigma);
  } else {
    std::fprintf(out, "confidence   none: the model has no confidence outputs (FORMAT.md 1.3)\n");
  }
}

void print_summary_json(const EvalSummary& s, FILE* out) {
  const auto obj = [&](const char* name, const ErrorStats& e) {
    std::fprintf(out,
                 ", \"%s\": {\"median\": %.4f, \"mean\": %.4f, \"p90\": %.4f, \"p99\": %.4f, "
                 "\"max\": %.4f, \"over_10\": %.4f, \"over_50\": %.4f}",
                 name, e.median, e.mean, e.p90, e.p99, e.max, e.over_10, e.over_50);
  };
  std::fprintf(out, "\"frames\": %zu, \"flagged_by_model\": %zu", s.frames, s.flagged_by_model);
  obj("position_m", s.position);
  obj("orientation_deg", s.orientation);
  std::fprintf(out,
               ", \"valid\": %zu, \"availability\": %.4f, \"first_valid_s\": %.3f, "
               "\"valid_over_10m\": %zu, \"valid_over_10deg\": %zu",
               s.valid, share(s.valid, s.frames), s.first_valid_s, s.valid_over_10m,
               s.valid_over_10deg);
  if (s.filtered) {
    std::fprintf(out, ", \"filtered\": true");
    obj("published_position_m", s.published_position);
    obj("published_orientation_deg", s.published_orientation);
  }
  obj("valid_position_m", s.valid_position);
  obj("valid_orientation_deg", s.valid_orientation);
  std::fprintf(
      out, ", \"coverage_frames\": %zu, \"coverage_position\": %.4f, \"coverage_yaw\": %.4f",
      s.with_sigma, share(s.inside_position, s.with_sigma), share(s.inside_yaw, s.with_sigma));
}

}  // namespace aprt::cli
