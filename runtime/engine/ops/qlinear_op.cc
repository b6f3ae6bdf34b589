// LINEAR with int8 weights (issue #4): the op's precision policy is in the file
// — an i8 weight tensor makes the op run int8 (FORMAT.md, "Quantised ops").
//   inputs: X f32 [.., K], W i8 [N, K] (symmetric, per-channel scales in the
//           f32 constant W.qscale_tensor, or one per-tensor scale), B f32 [N], R?
//   params: act, input scale (f32 bits, > 0), input zero point (0..255)
// eval: X is quantised to uint8 per tensor into scratch, multiplied by W with
// exact int32 accumulation, and requantised to f32 in the kernel's epilogue
// (y = mult[j] * acc + bias[j], mult[j] = input scale * weight scale[j]). ReLU
// and the residual fuse into the epilogue where the order allows; GELU, SiLU
// and sigmoid run as the fp32 activation kernel over the output afterwards.
// Fast path: the quantisation in row tasks, then product tasks each of which
// finishes its own tile (activation, residual) in blocks of kFinishRows rows
// right after computing them, while they are still in cache -- the same
// arithmetic per element as one pass over the whole output, on every thread.
#include "kernels/gemm/qs8_gemm.h"
#include "kernels/gemm/qu8s8_gemm__ref.h"
#include "kernels/rowwise/f32_elementwise__ref.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

struct QLinearState {
  kernels::GemmShape shape;
  kernels::Act act;        // of the op
  kernels::Act fused_act;  // what the kernel's epilogue applies (none or ReLU)
  bool fuse_residual;      // the kernel adds R (only when no activation follows)
  float a_scale, a_inv_scale;
  int32_t a_zero;
  Split rows, panels;
  Split qrows;  // rows of the input quantisation per task
  // Offsets in node.packed (floats): mult[N], colsum[N] (int32), packed weights.
  size_t mult_at, colsum_at, weights_at;
};

struct QLinearTask {
  const OpNode* node;
  kernels::QGemmArgs args;
  uint8_t* q;  // the quantised input (args.a), written by quantize_task
};

const float* residual_of(const OpNode& node) {
  return node.n_in > 3 && node.in[3] ? node.in[3]->f32() : nullptr;
}

// After the product: the activation the epilogue could not fuse, then the
// residual that must follow it, on the output elements [i0, i1).
void finish(const OpNode& node, const QLinearState& s, size_t i0, size_t i1) {
  float* y = node.out[0]->f32();
  if (s.act != s.fused_act) {
    if (node.ks) {
      node.ks->activation(s.act, y, y, i0, i1);
    } else {
      kernels::f32_activation__ref(i1 - i0, s.act, y + i0, y + i0);
    }
  }
  const float* r = residual_of(node);
  if (r && !s.fuse_residual) {
    if (node.ks) {
      node.ks->add(y, r, y, i0, i1);
    } else {
      kernels::f32_add__ref(i1 - i0, y + i0, r + i0, y + i0);
    }
  }
}

bool needs_finish(const OpNode& node, const QLinearState& s) {
  return s.act != s.fused_act || (residual_of(node) && !s.fuse_residual);
}

// Rows a product task computes before finishing them: 128 rows of 256
// outputs are 128 KB, in L2 when the activation reads them back.
constexpr int kFinishRows = 128;

void eval_qlinear_ref(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<QLinearState>();
  const size_t mk = size_t(s.shape.m) * s.shape.k;
  auto* q = reinterpret_cast<uint8_t*>(ctx.scratch);
  kernels::f32_qu8_quantize__ref(mk, node.in[0]->f32(), s.a_inv_scale, s.a_zero, q);
  kernels::qu8s8_gemm__ref(s.shape.m, s.shape.n, s.shape.k, q, size_t(s.shape.k), s.a_zero,
                           static_cast<const int8_t*>(node.in[1]->data), node.packed + s.mult_at,
                           node.in[2]->f32(), s.fuse_residual ? residual_of(node) : nullptr,
                           size_t(s.shape.n), s.fused_act, node.out[0]->f32(), size_t(s.shape.n));
  finish(node, s, 0, node.out[0]->numel);
}

void quantize_task(void* data, int task, int) {
  const auto* t = static_cast<const QLinearTask*>(data);
  const OpNode& node = *t->node;
  const auto& s = node.state_as<QLinearState>();
  const size_t k = size_t(s.shape.k), r0 = size_t(s.qrows.begin(task));
  node.qks->quantize((size_t(s.qrows.end(task)) - r0) * k, node.in[0]->f32() + r0 * k,
                     s.a_inv_scale, s.a_zero, t->q + r0 * k);
}

void qlinear_task(void* data, int task, int) {
  const auto* t = static_cast<const QLinearTask*>(data);
  const OpNode& node = *t->node;
  const auto& s = node.state_as<QLinearState>();
  const int rt = task % s.rows.tasks, pt = task / s.rows.tasks;
  const int r0 = s.rows.begin(rt), r1 = s.rows.end(rt), p0 = s.panels.begin(pt),
            p1 = s.panels.end(pt);
  if (!needs_finish(node, s)) {
    node.qks->gemm(t->args, r0, r1, p0, p1);
    return;
  }
  const size_t n = size_t(s.shape.n);
  const size_t c0 = size_t(p0) * node.qks->nr;
  const size_t c1 = size_t(p1) * node.qks->nr < n ? size_t(p1) * node.qks->nr : n;
  for (int b0 = r0; b0 < r1; b0 += kFinishRows) {
    const int b1 = b0 + kFinishRows < r1 ? b0 + kFinishRows : r1;
    node.qks->gemm(t->args, b0, b1, p0, p1);
    if (c0 == 0 && c1 == n) {
      finish(node, s, size_t(b0) * n, size_t(b1) * n);
    } else {
      for (int r = b0; r < b1; ++r) finish(node, s, size_t(r) * n + c0, size_t(r) * n + c1);
    }
  }
}

void eval_qlinear_fast(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<QLinearState>();
  auto* q = reinterpret_cast<uint8_t*>(ctx.scratch);
  const float* packed = node.packed;
  QLinearTask t{&node,
                {s.shape.m, s.shape.n, s.shape.k, q, size_t(s.shape.k), s.a_zero,
                 reinterpret_cast<const int8_t*>(packed + s.weights_at),
                 reinterpret_cast<const int32_t*>(packed + s.colsum_at), packed + s.mult_at,
                 node.in[2]->f32(), s.fuse_residual ? residual_of(node) : nullptr,
                 size_t(s.shape.n), node.out[0]->f32(), size_t(s.shape.n), s.fused_act},
                q};
  parallel_for(ctx, s.qrows.tasks, quantize_task, &t);
  parallel_for(ctx, s.rows.tasks * s.panels.tasks, qlinear_task, &t);
}

// mult[j] = input scale x weight scale[j], as one float product (the converter's
// simulation computes the same); then the column sums and the packed weights.
void pack_qlinear(OpNode& node) {
  const auto& s = node.state_as<QLinearState>();
  const Tensor* w = node.in[1];
  float* mult = node.packed + s.mult_at;
  for (int j = 0; j < s.shape.n; ++j) {
    const float ws = w->qscale ? w->qscale->f32()[j] : w->scale;
    mult[j] = s.a_scale * ws;
  }
  const auto* wq = static_cast<const int8_t*>(w->data);
  if (!node.qks) return;  // the reference kernel reads W as stored
  kernels::qs8_column_sums(s.shape.n, s.shape.k, wq,
                           reinterpret_cast<int32_t*>(node.packed + s.colsum_at));
  kernels::qs8_pack_w(s.shape.n, s.shape.k, node.qks->nr, node.qks->kgroup, wq,
                      reinterpret_cast<int8_t*>(node.packed + s.weights_at));
}

}  // namespace

Status prepare_qlinear(OpNode& node) {
  const Tensor* x = node.in[0];
  const Tensor* w = node.in[1];
  const Tensor* b = node.in[2];
  const Tensor* y = node.out[0];
  Status st;
  if (!(st = expect_f32(node, x, "input", false))) return st;
  APRT_OP_ENSURE(node, w->is_const() && w->rank == 2, Errc::kShapeMismatch,
                 "int8 weights '%s' must be a constant [N, K]", w->name);
  const int n = w->dims[0], k = w->dims[1];
  if (!(st = expect_int8_weights(node, w, n))) return st;
  if (!(st = expect_f32(node, b, "bias", true))) return st;
  if (!(st = expect_f32(node, y, "output", false))) return st;
  if (!(st = expect_act(node, node.params[0]))) return st;
  const int bd[1] = {n};
  if (!(st = expect_dims(node, b, "bias", 1, bd))) return st;
  APRT_OP_ENSURE(node, x->last_dim() == k, Errc::kShapeMismatch,
                 "input '%s' rows have %d values, weights expect %d", x->name, x->last_dim(), k);
  APRT_OP_ENSURE(node, y->last_dim() == n && y->numel == x->rows() * size_t(n),
                 Errc::kShapeMismatch, "output '%s' must be %zu x %d", y->name, x->rows(), n);
  const bool has_residual = node.n_in > 3 && node.in[3];
  if (has_residual) {
    if (!(st = expect_f32(node, node.in[3], "residual", false))) return st;
    APRT_OP_ENSURE(node, node.in[3]->numel == y->numel, Errc::kShapeMismatch,
                   "residual has %zu elements, output %zu", node.in[3]->numel, y->numel);
  }
  float a_scale;
  int32_t a_zero;
  if (!(st = expect_input_quantisation(node, 1, &a_scale, &a_zero))) return st;
  auto& s = node.state_as<QLinearState>();
  s.shape = {int(x->rows()), n, k};
  s.act = static_cast<kernels::Act>(node.params[0]);
  // The kernel's epilogue is (acc * mult + bias + R), then ReLU: it can apply
  // ReLU only without a residual (LINEAR adds R after the activation).
  const bool act_fusable =
      s.act == kernels::Act::kNone || (s.act == kernels::Act::kRelu && !has_residual);
  s.fused_act = act_fusable ? s.act : kernels::Act::kNone;
  s.fuse_residual = has_residual && s.act == kernels::Act::kNone;
  s.a_scale = a_scale;
  s.a_inv_scale = 1.0f / a_scale;
  s.a_zero = a_zero;
  node.flops = 2ull * x->rows() * n * k;
  node.scratch_floats = floats_for_bytes(size_t(s.shape.m) * k);
  s.mult_at = 0;
  s.colsum_at = floats_for_bytes(size_t(n) * 4);
  s.weights_at = s.colsum_at + floats_for_bytes(size_t(n) * 4);
  node.pack = pack_qlinear;
  if (node.qks) {
    split_gemm(s.shape.m, n, k, node.qks->mr, node.qks->nr, node.threads, &s.rows, &s.panels);
    // Rows in units of 16 (whole quantiser vectors of the widths that matter;
    // any split is exact), at most one task per thread.
    s.qrows = make_split(s.shape.m, 16, node.threads);
    node.packed_floats = s.weights_at + floats_for_bytes(kernels::qs8_pack_w_bytes(
                                            n, k, node.qks->nr, node.qks->kgroup));
    node.packed_inputs = 1u << 1;
    node.packed_layout = "f32 scales + s32 column sums + s8 weight panels [n/nr][k/g][nr][g]";
    node.packed_tile = node.qks->nr;
    node.eval = eval_qlinear_fast;
    node.kernel = node.qks->isa;
  } else {
    node.packed_floats = s.colsum_at;  // mult only
    node.packed_layout = "f32 output scales";
    node.eval = eval_qlinear_ref;
    node.kernel = "ref-int8";
  }
  return ok();
}

}  // namespace aprt::ops
