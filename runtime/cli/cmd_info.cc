// aprt info MODEL [--ops] [--json]
#include <cstdio>
#include <cstring>

#include "runtime/cli/args.h"
#include "runtime/cli/commands.h"
#include "runtime/engine/engine.h"

namespace aprt::cli {
namespace {

void shape_text(const Tensor& t, char* buf, size_t n) {
  size_t used = 0;
  buf[0] = '\0';
  for (int d = 0; d < t.rank && used < n; ++d) {
    used += size_t(std::snprintf(buf + used, n - used, "%s%d", d ? "x" : "", t.dims[d]));
  }
}

const char* resize_text(format::ResizePolicy p) {
  return p == format::ResizePolicy::kStretch ? "stretch to square"
                                             : "shorter side to size, centre crop";
}

double mb(size_t bytes) {
  return double(bytes) / 1e6;
}

// Where the file's bytes and the engine's block go: every weight once, kept as
// stored or packed into the layout of the kernel chosen on this CPU.
void print_memory(const Engine& e) {
  const MemoryReport& r = e.memory();
  size_t by_dtype[8] = {};
  for (size_t i = 0; i < e.tensor_count(); ++i) {
    const Tensor& t = e.tensor(i);
    if (t.is_const() && size_t(t.dtype) < 8) by_dtype[size_t(t.dtype)] += t.bytes;
  }
  std::printf("file         %.2f MB: weights %.2f (", mb(r.file_bytes), mb(r.weight_bytes));
  bool first = true;
  for (size_t d = 0; d < 8; ++d) {
    if (!by_dtype[d]) continue;
    std::printf("%s%s %.2f", first ? "" : ", ", format::dtype_name(format::DType(d)),
                mb(by_dtype[d]));
    first = false;
  }
  std::printf("), tables %.3f\n", mb(r.file_bytes - r.weight_bytes));
  std::printf(
      "memory       %.2f MB in one block: tables %.3f + weights kept as stored %.3f (%zu "
      "tensors) + packed %.2f (%zu ops) + arena %.3f + scratch %.3f\n",
      mb(r.total_bytes), mb(r.tables_bytes), mb(r.kept_bytes), r.kept_count, mb(r.packed_bytes),
      r.packed_count, mb(r.arena_bytes), mb(r.scratch_bytes));
  // The packed layouts, in order of first use.
  const char* layouts[8] = {};
  int tiles[8] = {}, ops[8] = {};
  size_t bytes[8] = {};
  int kinds = 0;
  for (size_t i = 0; i < e.op_count(); ++i) {
    const OpNode& n = e.op(i);
    if (!n.packed_floats) continue;
    int at = 0;
    while (at < kinds &&
           !(std::strcmp(layouts[at], n.packed_layout) == 0 && tiles[at] == n.packed_tile))
      ++at;
    if (at == kinds && kinds < 8) {
      layouts[kinds] = n.packed_layout;
      tiles[kinds++] = n.packed_tile;
    }
    if (at < kinds) {
      ++ops[at];
      bytes[at] += n.packed_floats * sizeof(float);
    }
  }
  for (int i = 0; i < kinds; ++i) {
    char tile[24] = "";
    if (tiles[i]) std::snprintf(tile, sizeof tile, ", nr %d", tiles[i]);
    std::printf("%s %s%s: %d ops, %.3f MB\n", i ? "            " : "packed      ", layouts[i], tile,
                ops[i], mb(bytes[i]));
  }
}

}  // namespace

int cmd_info(int argc, char** argv) {
  Args args(argc, argv);
  if (args.flag("--help")) {
    std::printf("usage: aprt info MODEL [--ops]\n  --ops   list every op with its shapes\n");
    return 0;
  }
  const bool list_ops = args.flag("--ops");
  const char* path = args.positional();
  if (args.refuse("info")) return 2;
  if (!path) {
    std::fprintf(stderr, "aprt info: missing MODEL (usage: aprt info MODEL [--ops])\n");
    return 2;
  }
  EngineOptions opts;
  opts.lock_memory = false;
  auto loaded = Engine::load_file(path, opts);
  if (!loaded) {
    std::fprintf(stderr, "aprt info: %s\n", loaded.error().message());
    return 2;
  }
  const Engine& e = *loaded.value();
  const ModelMeta& m = e.meta();
  const ModelFile& f = e.model();
  std::printf("model        %s\n", path);
  std::printf("format       model_bin %u.%u, %.2f MB, produced by %s\n", f.version_major(),
              f.version_minor(), double(f.file_bytes()) / 1e6, m.producer);
  std::printf("source       %s sha256 ", m.source_name[0] ? m.source_name : "?");
  for (uint8_t b : m.source_sha256) std::printf("%02x", b);
  std::printf("\n");
  std::printf("modality     %s, input %ux%ux%ux%u (NHWC f32)\n", format::modality_name(m.modality),
              m.input_shape[0], m.input_shape[1], m.input_shape[2], m.input_shape[3]);
  if (m.has_bev) {
    std::printf(
        "bev          %u x %u cells of %.4g m from (%.4g, %.4g) m, channel 1 at z >= %.4g m, "
        "counts clipped at %.4g\n",
        m.input_shape[1], m.input_shape[2], double(m.bev_cell_m), double(m.bev_x_min),
        double(m.bev_y_min), double(m.bev_height_threshold_m), double(m.bev_clip_count));
  } else if (m.has_points) {
    std::printf(
        "points       %u farthest-point samples of the scan within %.4g m (x^2 + y^2), features "
        "p / %.4g m and (p - mean) / %.4g m\n",
        m.input_shape[1], double(m.points_crop_radius_m), double(m.points_coord_scale_m),
        double(m.points_coord_scale_m));
  } else {
    std::printf("normalise    mean (");
    for (int c = 0; c < m.norm_channels; ++c) std::printf("%s%.4g", c ? ", " : "", m.norm_mean[c]);
    std::printf(") std (");
    for (int c = 0; c < m.norm_channels; ++c) std::printf("%s%.4g", c ? ", " : "", m.norm_std[c]);
    std::printf("), %s\n", resize_text(m.resize_policy));
  }
  std::printf(
      "network      %s, d_model %u, %u heads, %u encoder + %u decoder layers, "
      "feed-forward %u\n",
      m.backbone[0] ? m.backbone : "?", m.d_model, m.nheads, m.enc_layers, m.dec_layers,
      m.dim_feedforward);
  std::printf("pose bounds  min (%.3f, %.3f, %.3f) max (%.3f, %.3f, %.3f) m\n", m.pose_min[0],
              m.pose_min[1], m.pose_min[2], m.pose_max[0], m.pose_max[1], m.pose_max[2]);
  if (m.has_val_error) {
    std::printf("validation   median error %.3f m, %.3f deg\n", m.val_error_position_m,
                m.val_error_orientation_deg);
  } else {
    std::printf("validation   no measured error in the file\n");
  }
  if (m.ensemble_members > 0) {
    std::printf("ensemble     %u networks (aprt_tools ensemble)%s\n", unsigned(m.ensemble_members),
                m.member_outputs > 0 ? ", merged at run time, their spread in the confidence"
                                     : ", averaged in the graph");
  }
  if (m.has_uncertainty) {
    std::printf(
        "confidence   per pose: 13 outputs, calibration k %.3f (position), %.3f (rotation)\n",
        double(m.uncertainty_scale[0]), double(m.uncertainty_scale[1]));
  } else {
    std::printf("confidence   none: the published covariance is the validation error\n");
  }

  if (m.quantization) {
    size_t int8_ops = 0;
    for (size_t i = 0; i < e.op_count(); ++i) {
      const OpNode& n = e.op(i);
      if (n.n_in > 1 && n.in[1] && n.in[1]->dtype == format::DType::kI8) ++int8_ops;
    }
    std::printf("int8         %zu ops with int8 weights; %.*s\n", int8_ops,
                int(m.quantization_bytes > 300 ? 300 : m.quantization_bytes), m.quantization);
  }
  int counts[format::kMaxOpCode + 1] = {};
  for (size_t i = 0; i < e.op_count(); ++i) counts[int(e.op(i).code)]++;
  std::printf("ops          %zu:", e.op_count());
  for (int c = 1; c <= format::kMaxOpCode; ++c) {
    if (counts[c]) std::printf(" %s %d", format::op_name(format::OpCode(c)), counts[c]);
  }
  std::printf("\n");
  // Which implementation each op runs on this CPU (chosen at load: the fp32,
  // int8 and bf16 tables, or the reference), in order of first use.
  const char* kernel_names[8] = {};
  int kernel_ops[8] = {};
  int kinds = 0;
  for (size_t i = 0; i < e.op_count(); ++i) {
    const char* k = e.op(i).kernel;
    int at = 0;
    while (at < kinds && std::strcmp(kernel_names[at], k) != 0) ++at;
    if (at == kinds && kinds < 8) kernel_names[kinds++] = k;
    if (at < kinds) ++kernel_ops[at];
  }
  std::printf("kernels      on this CPU:");
  for (int i = 0; i < kinds; ++i)
    std::printf("%s %s %d", i ? "," : "", kernel_names[i], kernel_ops[i]);
  std::printf(" ops\n");
  std::printf("compute      %.3f G multiply-adds per frame\n", double(e.total_flops()) / 2e9);
  const MemoryReport& r = e.memory();
  size_t n_const = 0;
  for (size_t i = 0; i < e.tensor_count(); ++i) n_const += e.tensor(i).is_const();
  std::printf("tensors      %zu (%zu constants, %.2f MB weights)\n", e.tensor_count(), n_const,
              double(r.weight_bytes) / 1e6);
  std::printf(
      "arena        %.3f MB planned; %.3f MB if every tensor had its own buffer; "
      "%.3f MB liveness lower bound\n",
      double(r.arena_bytes) / 1e6, double(r.arena_sum_bytes) / 1e6,
      double(r.arena_lower_bound_bytes) / 1e6);
  print_memory(e);
  if (list_ops) {
    std::printf("\n  #  op              MFLOP  output          kernel      name\n");
    for (size_t i = 0; i < e.op_count(); ++i) {
      const OpNode& n = e.op(i);
      char shape[48];
      shape_text(*n.out[0], shape, sizeof shape);
      std::printf("%4zu %-14s %7.2f  %-15s %-11s %s\n", i, format::op_name(n.code),
                  double(n.flops) / 1e6, shape, n.kernel, n.name);
    }
  }
  return 0;
}

}  // namespace aprt::cli
