// ATTENTION: multi-head softmax(scale Q K^T) V over row-major Q [Lq,E], K/V [Lk,E].
// params: heads, scale (f32 bits)
// Fast path: K and V are packed per head into the op's scratch (K^T in key
// blocks; tasks over heads), then (head, query chunk) tasks run the fused
// online-softmax kernel.
#include "kernels/ref/f32_attention__ref.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

struct AttnState {
  kernels::AttentionShape shape;
  float scale;
  int lk_pad;
  Split chunks;  // query rows per task, whole row groups, at most attn_max_rows
};

void eval_attention_ref(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<AttnState>();
  kernels::f32_attention__ref(s.shape, node.in[0]->f32(), node.in[1]->f32(), node.in[2]->f32(),
                              s.scale, node.out[0]->f32(), ctx.scratch);
}

struct AttnTask {
  const OpNode* node;
  const RunContext* ctx;
};

void pack_task(void* data, int head, int) {
  const auto* t = static_cast<const AttnTask*>(data);
  const auto& s = t->node->state_as<AttnState>();
  const size_t e = size_t(s.shape.heads) * s.shape.head_dim;
  t->node->ks->attn_pack_kv(s.shape.kv_len, s.lk_pad, s.shape.head_dim, t->node->in[1]->f32(), e,
                            t->node->in[2]->f32(), e, head, t->ctx->scratch,
                            t->ctx->scratch + e * s.lk_pad);
}

void block_task(void* data, int task, int thread) {
  const auto* t = static_cast<const AttnTask*>(data);
  const OpNode& node = *t->node;
  const auto& s = node.state_as<AttnState>();
  const int e = s.shape.heads * s.shape.head_dim;
  const int h = task / s.chunks.tasks, c = task % s.chunks.tasks;
  const int q0 = s.chunks.begin(c), rows = s.chunks.end(c) - q0;
  float* kt = t->ctx->scratch;
  (void)node.ks->attn_block(rows, s.shape.kv_len, s.shape.head_dim, node.in[0]->f32(), size_t(e),
                            kt, kt + size_t(e) * s.lk_pad, s.lk_pad, s.scale, node.out[0]->f32(),
                            size_t(e), h, q0, t->ctx->thread_scratch[thread]);
}

void eval_attention_fast(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<AttnState>();
  AttnTask t{&node, &ctx};
  parallel_for(ctx, s.shape.heads, pack_task, &t);
  parallel_for(ctx, s.shape.heads * s.chunks.tasks, block_task, &t);
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
  node.flops = 4ull * q->rows() * k->rows() * e;
  const bool fast = node.ks && (s.shape.head_dim + node.ks->lanes - 1) / node.ks->lanes <= 8;
  if (fast) {
    const int step = node.ks->attn_key_block;
    s.lk_pad = (s.shape.kv_len + step - 1) / step * step;
    const int max_rows = node.ks->attn_max_rows;
    s.chunks = make_split(s.shape.q_len, node.ks->attn_group_rows,
                          (s.shape.q_len + max_rows - 1) / max_rows);
    node.scratch_floats = 2 * size_t(e) * s.lk_pad;  // packed K^T and V
    node.thread_scratch_floats = node.ks->attn_scratch(s.shape.head_dim);
    node.eval = eval_attention_fast;
    node.kernel = node.ks->isa;
  } else {
    node.scratch_floats = kernels::f32_attention__ref_scratch(s.shape);
    node.eval = eval_attention_ref;
  }
  return ok();
}

}  // namespace aprt::ops
