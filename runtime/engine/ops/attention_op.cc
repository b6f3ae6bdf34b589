// ATTENTION: multi-head softmax(scale Q K^T) V over row-major Q [Lq,E], K/V [Lk,E].
// params: heads, scale (f32 bits)
#include "kernels/ref/f32_attention__ref.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

struct AttnState {
  kernels::AttentionShape shape;
  float scale;
};

void eval_attention_ref(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<AttnState>();
  kernels::f32_attention__ref(s.shape, node.in[0]->f32(), node.in[1]->f32(), node.in[2]->f32(),
                              s.scale, node.out[0]->f32(), ctx.scratch);
}

}  // namespace

Status prepare_attention(OpNode& node) {
  const Tensor* q = node.in[0];
  const Tensor* k = node.in[1];
  const Tensor* v = node.in[2];
  const Tensor* y = node.out[0];
  Status st;
  for (const Tensor* t : {q, k, v}) {
    APRT_OP_ENSURE(node, t != nullptr && t->dtype == format::DType::kF32, Errc::kShapeMismatch,
                   "query, key and value must be f32 tensors");
  }
  if (!(st = expect_f32(node, y, "output", false))) return st;
  const int e = q->last_dim();
  const int heads = node.params[0];
  const float scale = param_f32(node, 1);
  APRT_OP_ENSURE(node, heads >= 1 && e % heads == 0, Errc::kBadOp,
                 "%d heads do not divide the width %d", heads, e);
  APRT_OP_ENSURE(node, std::isfinite(scale) && scale > 0.0f, Errc::kBadOp, "scale %g invalid",
                 scale);
  APRT_OP_ENSURE(node, k->last_dim() == e && v->last_dim() == e, Errc::kShapeMismatch,
                 "key/value width %d/%d differs from the query's %d", k->last_dim(), v->last_dim(),
                 e);
  APRT_OP_ENSURE(node, k->rows() == v->rows(), Errc::kShapeMismatch, "%zu keys but %zu values",
                 k->rows(), v->rows());
  APRT_OP_ENSURE(node, y->numel == q->numel && y->last_dim() == e, Errc::kShapeMismatch,
                 "output must be %zu x %d", q->rows(), e);
  auto& s = node.state_as<AttnState>();
  s.shape = {int(q->rows()), int(k->rows()), heads, e / heads};
  s.scale = scale;
  node.scratch_floats = kernels::f32_attention__ref_scratch(s.shape);
  node.flops = 4ull * q->rows() * k->rows() * e;
  node.eval = eval_attention_ref;
  return ok();
}

}  // namespace aprt::ops
