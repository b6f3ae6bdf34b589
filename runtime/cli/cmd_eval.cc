// aprt eval --model MODEL --data DIR [--compare MODEL2] [--csv FILE] [--json] [--threads N]
//           [--isa X] [--start N] [--every N] [--limit N] [--rate HZ|recorded]
//           [--config FILE]
//
// Runs the model on the frames of a labelled sequence -- camera (DeepLoc
// layout) or, for a LiDAR model (BEV or points), scans (lidar_poses.txt + KITTI/PCD) --
// and reports position and orientation errors (median, mean, p90, p99, max,
// shares beyond 10 and 50), the same for the poses the validity gate lets out
// as valid (runtime/pose/pose_gate.h, with the configuration's sanity.track,
// the sequence's clock from --rate or its times.txt), availability, and how often the
// published 95 % regions hold the errors; per-frame rows with --csv (plot
// them with `python3 -m aprt_tools plot-eval`). With
// --compare (e.g. the int8 model beside its fp32 source) the second model runs
// on the same preprocessed input: its errors side by side, and the per-frame
// deviation of its pose from the first model's (p50 / p99 / max).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "runtime/base/angles.h"
#include "runtime/cli/args.h"
#include "runtime/cli/commands.h"
#include "runtime/cli/eval_inputs.h"
#include "runtime/cli/eval_metrics.h"
#include "runtime/cli/open_model.h"
#include "runtime/config/config.h"
#include "runtime/engine/engine.h"
#include "runtime/engine/pose_decode.h"
#include "runtime/loop/estimator.h"
#include "runtime/pose/odometry_filter.h"
#include "runtime/pose/pose_gate.h"
#include "runtime/pose/pose_geometry.h"

namespace aprt::cli {
namespace {

double quat_angle_deg(const double* a, const double* b) {
  double d = 0;
  for (int i = 0; i < 4; ++i) d += a[i] * b[i];
  d = std::min(1.0, std::fabs(d));
  return 2.0 * std::acos(d) * 180.0 / M_PI;
}

struct Stats {
  double median, mean, p90, p99, max;
};

Stats stats(std::vector<double> v) {
  if (v.empty()) return {0, 0, 0, 0, 0};
  std::sort(v.begin(), v.end());
  double sum = 0;
  for (double x : v) sum += x;
  auto q = [&](double p) {
    return v[std::min(v.size() - 1, size_t(p * double(v.size() - 1) + 0.5))];
  };
  return {q(0.5), sum / double(v.size()), q(0.9), q(0.99), v.back()};
}

double distance(const double* a, const double* b) {
  double d = 0;
  for (int k = 0; k < 3; ++k) d += (a[k] - b[k]) * (a[k] - b[k]);
  return std::sqrt(d);
}

// The second model of --compare: same input, its own errors and its deviation.
struct Compared {
  std::unique_ptr<Engine> engine;
  std::vector<double> pos_err, rot_err, pos_dev, rot_dev;
  size_t flagged = 0;
  size_t not_compared = 0;  // frames either model flagged
};

bool same_input(const ModelMeta& a, const ModelMeta& b) {
  bool same = a.modality == b.modality && a.resize_policy == b.resize_policy &&
              a.norm_channels == b.norm_channels;
  same = same && a.bev_cell_m == b.bev_cell_m && a.bev_x_min == b.bev_x_min &&
         a.bev_y_min == b.bev_y_min && a.bev_height_threshold_m == b.bev_height_threshold_m &&
         a.bev_clip_count == b.bev_clip_count;
  for (int d = 0; d < 4; ++d) same = same && a.input_shape[d] == b.input_shape[d];
  for (int c = 0; c < a.norm_channels && same; ++c)
    same = a.norm_mean[c] == b.norm_mean[c] && a.norm_std[c] == b.norm_std[c];
  return same;
}

}  // namespace

int cmd_eval(int argc, char** argv) {
  Args args(argc, argv);
  if (args.flag("--help")) {
    std::printf(
        "usage: aprt eval --model MODEL --data DIR [options]\n"
        "  DIR           camera: poses.txt + images (DeepLoc layout); LiDAR model (BEV\n"
        "                or points): lidar_poses.txt + scans (KITTI .bin or PCD), as\n"
        "                aprt_synth --lidar\n"
        "  --csv FILE    per-frame predictions, truth, errors and the published sigmas\n"
        "  --json        summary as one JSON object\n"
        "  --compare M2  also run model M2 (e.g. its int8 version) on the same input:\n"
        "                its errors side by side and its deviation from MODEL\n"
        "  --start N     begin at frame N (0-based)\n"
        "  --every N     take every N-th frame from there\n"
        "  --limit N     at most N frames\n"
        "  --rate HZ     the sequence's frame rate for the validity gate's clock\n"
        "                (default 25, the demo drive's); recorded: its times.txt\n"
        "  --config FILE the validity gate's parameters (sanity.track, max_jump_m) and\n"
        "                the pose filter's (sanity.filter: needs DIR/odometry.txt) from a\n"
        "                configuration (default: the built-in defaults)\n"
        "  --threads N   --isa NAME   as for aprt bench\n"
        "A pose is valid when neither the model (non-finite, out of the map, degenerate\n"
        "quaternion) nor the validity gate (jump, uncertain, inconsistent with the\n"
        "motion, unconfirmed) flagged it: what aprt run publishes as valid. With\n"
        "sanity.filter enabled the published pose is the filter's (the model's estimates\n"
        "and the vehicle's odometry): 'published' gives its errors on every frame, the\n"
        "valid poses and the confidence are its.\n");
    return 0;
  }
  const char* model_path = args.value("--model");
  const char* data = args.value("--data");
  const char* csv_path = args.value("--csv");
  const bool json = args.flag("--json");
  const long limit = args.integer("--limit", 0, 0, 100000000);
  const long start = args.integer("--start", 0, 0, 100000000);
  const long every = args.integer("--every", 1, 1, 100000);
  // "recorded": the sequence's own times (times.txt), e.g. a real drive's
  // time stamps or a synthetic drive's speed profile (aprt_tools drive-times).
  const char* rate_text = args.value("--rate");
  const bool recorded = rate_text && std::strcmp(rate_text, "recorded") == 0;
  const double rate = recorded ? 25.0 : args.number("--rate", 25.0, 0.01, 10000.0);
  const char* config_path = args.value("--config");
  const long threads = args.integer("--threads", 1, 1, 16);
  const char* isa = args.value("--isa");
  const char* compare_path = args.value("--compare");
  if (args.refuse("eval")) return 2;
  if (!model_path || !data) {
    std::fprintf(stderr, "aprt eval: --model and --data are required (aprt eval --help)\n");
    return 2;
  }
  Config gate_config;
  if (config_path) {
    auto c = load_config(config_path);
    if (!c) {
      std::fprintf(stderr, "aprt eval: %s\n", c.error().message());
      return 2;
    }
    gate_config = c.value();
  }
  PoseGate gate(pose_gate_params(gate_config));
  std::unique_ptr<Engine> engine = open_model("eval", model_path, int(threads), isa);
  if (!engine) return 2;
  Engine& e = *engine;
  Compared cmp;
  if (compare_path) {
    cmp.engine = open_model("eval", compare_path, int(threads), isa);
    if (!cmp.engine) return 2;
    if (!same_input(e.meta(), cmp.engine->meta())) {
      std::fprintf(stderr,
                   "aprt eval: %s and %s take different inputs (modality, shape, resize or "
                   "normalisation): nothing to compare frame by frame\n",
                   model_path, compare_path);
      return 2;
    }
  }
  std::unique_ptr<EvalInputs> inputs = open_eval_inputs(data, e);
  if (!inputs) return 2;
  const ModelMeta& m = e.meta();
  const bool filtered = gate_config.sanity.filter.enabled;
  if (filtered && !inputs->has_odometry()) {
    std::fprintf(stderr,
                 "aprt eval: %s enables sanity.filter, but %s has no odometry.txt (the "
                 "vehicle's speed and yaw rate: python3 -m aprt_tools odometry %s writes one "
                 "for a synthetic drive)\n",
                 config_path, data, data);
    return 2;
  }
  const std::vector<Config::Camera> cameras = camera_list(gate_config);
  OdometryFilter filter(
      odometry_filter_params(gate_config, m),
      RigidTransform::from_xyz_rpy(cameras[0].sensor_xyz, cameras[0].sensor_rpy_deg).isometry());
  FILE* csv = nullptr;
  if (csv_path) {
    csv = std::fopen(csv_path, "w");
    if (!csv) {
      std::fprintf(stderr, "aprt eval: cannot write %s\n", csv_path);
      return 1;
    }
    std::fprintf(csv,
                 "name,x,y,z,qw,qx,qy,qz,gt_x,gt_y,gt_z,gt_qw,gt_qx,gt_qy,gt_qz,"
                 "position_error_m,orientation_error_deg,flags,sigma_x_m,sigma_y_m,"
                 "sigma_yaw_deg,published_x,published_y,published_yaw_deg,"
                 "published_position_error_m,published_orientation_error_deg,"
                 "published_sigma_x_m,published_sigma_y_m,published_sigma_yaw_deg\n");
  }
  std::vector<size_t> frames;
  for (size_t i = size_t(start); i < inputs->size(); i += size_t(every)) {
    if (limit > 0 && frames.size() >= size_t(limit)) break;
    frames.push_back(i);
  }
  if (frames.empty()) {
    std::fprintf(stderr, "aprt eval: --start %ld is past the %zu frames of %s\n", start,
                 inputs->size(), data);
    return 2;
  }
  if (recorded) {
    for (const size_t i : frames) {
      if (inputs->time_s(i) < 0) {
        std::fprintf(stderr,
                     "aprt eval: --rate recorded: %s has no times.txt (\"name seconds\" per "
                     "frame; LiDAR sequences have none): give the rate in Hz\n",
                     data);
        return 2;
      }
    }
  }
  const double t0 = recorded ? inputs->time_s(frames.front()) : 0.0;
  const size_t n = frames.size();
  std::vector<EvalSample> samples;
  size_t bad_frames = 0, flagged = 0;
  OdometryReading previous;  // the frame evaluated before's (the filter's motion is from it)
  for (const size_t i : frames) {
    EvalFrame f;
    const char* why = "";
    if (!inputs->fill(i, e, &f, &why)) {
      std::fprintf(stderr, "aprt eval: frame %zu skipped: %s\n", i, why);
      ++bad_frames;
      continue;
    }
    // The input's buffer is reused by later activations: copy it before run().
    if (cmp.engine) std::copy_n(e.input().f32(), e.input().numel, cmp.engine->input().f32());
    (void)e.run();
    const PoseEstimate p = decode_pose(e.output().f32(), m);
    if (!p.valid()) ++flagged;
    const double pe = distance(p.position, f.position);
    const double oe = quat_angle_deg(p.orientation, f.orientation);
    EvalSample smp;
    smp.t_s = recorded ? inputs->time_s(i) - t0 : double(i) / rate;
    smp.position_error_m = pe;
    smp.orientation_error_deg = oe;
    uint32_t all_flags = 0;
    PoseEstimate out = p;  // what goes out
    if (filtered) {
      const OdometryReading reading = inputs->odometry(i);
      PlanarMotion motion;
      const bool moved = motion_between(previous, reading, &motion);
      previous = reading;
      const FilteredPose fp = filter.step(p, p.flags, moved ? &motion : nullptr);
      out = fp.sensor;
      all_flags = fp.flags;
    } else {
      all_flags = gate.apply(p, smp.t_s, p.flags);
    }
    smp.published_position_error_m = distance(out.position, f.position);
    smp.published_orientation_error_deg = quat_angle_deg(out.orientation, f.orientation);
    smp.valid = all_flags == 0;
    smp.has_sigma = out.has_sigma;
    if (out.has_sigma) {
      coverage_of(out, f.position, f.orientation, &smp.inside_position, &smp.inside_yaw);
    }
    samples.push_back(smp);
    if (cmp.engine) {
      Engine& c = *cmp.engine;
      (void)c.run();
      const PoseEstimate q = decode_pose(c.output().f32(), c.meta());
      if (!q.valid()) ++cmp.flagged;
      cmp.pos_err.push_back(distance(q.position, f.position));
      cmp.rot_err.push_back(quat_angle_deg(q.orientation, f.orientation));
      // A flagged estimate (e.g. a quaternion norm outside the sanity range)
      // has no meaningful orientation to compare; such frames are counted.
      if (p.valid() && q.valid()) {
        cmp.pos_dev.push_back(distance(q.position, p.position));
        cmp.rot_dev.push_back(quat_angle_deg(q.orientation, p.orientation));
      } else {
        ++cmp.not_compared;
      }
    }
    if (csv) {
      std::fprintf(
          csv,
          "%s,%.4f,%.4f,%.4f,%.6f,%.6f,%.6f,%.6f,%.4f,%.4f,%.4f,%.6f,%.6f,%.6f,%.6f,%.4f,%.4f,%u,"
          "%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f\n",
          f.name, p.position[0], p.position[1], p.position[2], p.orientation[0], p.orientation[1],
          p.orientation[2], p.orientation[3], f.position[0], f.position[1], f.position[2],
          f.orientation[0], f.orientation[1], f.orientation[2], f.orientation[3], pe, oe, all_flags,
          p.sigma_position_m[0], p.sigma_position_m[1], p.sigma_rotation_rad[2] * 180.0 / M_PI,
          out.position[0], out.position[1], quaternion_yaw(out.orientation) * 180.0 / M_PI,
          smp.published_position_error_m, smp.published_orientation_error_deg,
          out.has_sigma ? out.sigma_position_m[0] : -1.0,
          out.has_sigma ? out.sigma_position_m[1] : -1.0,
          out.has_sigma ? out.sigma_rotation_rad[2] * 180.0 / M_PI : -1.0);
    }
  }
  if (csv) std::fclose(csv);
  const EvalSummary sum = summarise(samples, flagged, filtered);
  const Stats cps = stats(cmp.pos_err), cos = stats(cmp.rot_err);
  const Stats dps = stats(cmp.pos_dev), dos = stats(cmp.rot_dev);
  if (json) {
    std::printf("{\"model\": \"%s\", \"data\": \"%s\", \"skipped\": %zu, \"isa\": \"%s\", ",
                model_path, data, bad_frames, e.isa());
    print_summary_json(sum, stdout);
    if (cmp.engine) {
      std::printf(
          ", \"compare\": {\"model\": \"%s\", \"flagged\": %zu, \"position_m\": {\"median\": "
          "%.4f, \"mean\": %.4f, \"p90\": %.4f, \"max\": %.4f}, \"orientation_deg\": "
          "{\"median\": %.4f, \"mean\": %.4f, \"p90\": %.4f, \"max\": %.4f}, "
          "\"compared_frames\": %zu, \"deviation_position_m\": {\"p50\": %.5f, \"p99\": %.5f, "
          "\"max\": %.5f}, "
          "\"deviation_orientation_deg\": {\"p50\": %.5f, \"p99\": %.5f, \"max\": %.5f}}",
          compare_path, cmp.flagged, cps.median, cps.mean, cps.p90, cps.max, cos.median, cos.mean,
          cos.p90, cos.max, cmp.pos_dev.size(), dps.median, dps.p99, dps.max, dos.median, dos.p99,
          dos.max);
    }
    std::printf("}\n");
  } else {
    std::printf("model        %s (%s kernels)\n", model_path, e.isa());
    std::printf(
        "sequence     %s: %zu frames evaluated (from %ld, every %ld), %zu skipped, %zu "
        "flagged by the model\n",
        data, samples.size(), start, every, bad_frames, flagged);
    print_summary(sum, stdout);
    if (cmp.engine) {
      std::printf("compare      %s (%s kernels), %zu flagged\n", compare_path, cmp.engine->isa(),
                  cmp.flagged);
      std::printf("position     median %.2f m  mean %.2f m  p90 %.2f m  max %.2f m\n", cps.median,
                  cps.mean, cps.p90, cps.max);
      std::printf("orientation  median %.2f deg  mean %.2f deg  p90 %.2f deg  max %.2f deg\n",
                  cos.median, cos.mean, cos.p90, cos.max);
      std::printf("deviation    %zu frames both unflagged (%zu left out)\n", cmp.pos_dev.size(),
                  cmp.not_compared);
      std::printf("             position p50 %.4f  p99 %.4f  max %.4f m\n", dps.median, dps.p99,
                  dps.max);
      std::printf("             orientation p50 %.4f  p99 %.4f  max %.4f deg\n", dos.median,
                  dos.p99, dos.max);
    }
  }
  return bad_frames == n ? 1 : 0;
}

}  // namespace aprt::cli
