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
#include "kernels/common/qkernel_set.h"
#include "kernels/ref/f32_elementwise__ref.h"
#include "kernels/ref/qs8_gemm__ref.h"
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
  // Offsets in node.packed (floats): mult[N], colsum[N] (int32), packed weights.
  size_t mult_at, colsum_at, weights_at;
};

struct QLinearTask {
  const OpNode* node;
  kernels::QGemmArgs args;
};

const float* residual_of(const OpNode& node) {
  return node.n_in > 3 && node.in[3] ? node.in[3]->f32() : nullptr;
}

// After the product: the activation the epilogue could not fuse, then the
// residual that must follow it. Serial: O(M N), small beside the product.
void finish(const OpNode& node, const QLinearState& s) {
  float* y = node.out[0]->f32();
  const size_t n = node.out[0]->numel;
  if (s.act != s.fused_act) {
    if (node.ks) {
      node.ks->activation(s.act, y, y, 0, n);
    } else {
      kernels::f32_activation__ref(n, s.act, y, y);
    }
  }
  const float* r = residual_of(node);
  if (r && !s.fuse_residual) {
    if (node.ks) {
      node.ks->add(y, r, y, 0, n);
    } else {
      kernels::f32_add__ref(n, y, r, y);
    }
  }
}

void eval_qlinear_ref(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<QLinearState>();
  const size_t mk = size_t(s.shape.m) * s.shape.k;
  auto* q = reinterpret_cast<uint8_t*>(ctx.scratch);
  kernels::f32_qu8_quantize__ref(mk, node.in[0]->f32(), s.a_inv_scale, s.a_zero, q);
  kernels::qu8s8_gemm__ref(s.shape.m, s.shape.n, s.shape.k, q, size_t(s.shape.k), s.a_zero,
                           static_cast<const int8_t*>(node.in[1]->data), node.packed + s.mult_at,
                           node.in[2]->f32(), s.fuse_residual ? residual_of(node) : nullptr,
                           size_t(s.shape.n), s.fused_act, node.out[0]->f32(), size_t(s.shape.n));
  finish(node, s);
}

void qlinear_task(void* data, int task, int) {
  const auto* t = static_cast<const QLinearTask*>(data);
  const auto& s = t->node->state_as<QLinearState>();
  const int rt = task % s.rows.tasks, pt = task / s.rows.tasks;
  t->node->qks->gemm(t->args, s.rows.begin(rt), s.rows.end(rt), s.panels.begin(pt),
                     s.panels.end(pt));
}

void eval_qlinear_fast(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<QLinearState>();
  auto* q = reinterpret_cast<uint8_t*>(ctx.scratch);
  node.qks->quantize(size_t(s.shape.m) * s.shape.k, node.in[0]->f32(), s.a_inv_scale, s.a_zero, q);
  const float* packed = node.packed;
  QLinearTask t{&node,
                {s.shape.m, s.shape.n, s.shape.k, q, size_t(s.shape.k), s.a_zero,
                 reinterpret_cast<const int8_t*>(packed + s.weights_at),
                 reinterpret_cast<const int32_t*>(packed + s.colsum_at), packed + s.mult_at,
                 node.in[2]->f32(), s.fuse_residual ? residual_of(node) : nullptr,
                 size_t(s.shape.n), node.out[0]->f32(), size_t(s.shape.n), s.fused_act}};
  parallel_for(ctx, s.rows.tasks * s.panels.tasks, qlinear_task, &t);
  finish(node, s);
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
    node.packed_floats = s.weights_at + floats_for_bytes(kernels::qs8_pack_w_bytes(
                                            n, k, node.qks->nr, node.qks->kgroup));
    node.eval = eval_qlinear_fast;
    node.kernel = node.qks->isa;
  } else {
    node.packed_floats = s.colsum_at;  // mult only
    node.eval = eval_qlinear_ref;
    node.kernel = "ref-int8";
  }
  return ok();
}

}  // namespace aprt::ops
