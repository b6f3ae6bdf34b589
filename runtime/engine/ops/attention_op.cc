// ATTENTION: multi-head softmax(scale Q K^T) V over row-major Q [Lq,E], K/V [Lk,E].
// params: heads, scale (f32 bits), scores (0 fp32, 1 int8: kernels/common/qs8_attention.h)
// Fast path: K and V are packed per head into the op's scratch (K^T in key
// blocks; tasks over heads), then (head, query chunk) tasks run the fused
// online-softmax kernel. int8 scores: the int8 table's kernel where it has one
// (AVX-512 VNNI), else Q and K fake-quantised into scratch and the fp32 path
// over them -- the same scores up to the rounding of fp32 products of small
// integers.
#include "kernels/common/qkernel_set.h"
#include "kernels/ref/f32_attention__ref.h"
#include "kernels/ref/qs8_attention__ref.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

enum class Scores : uint8_t { kF32, kInt8Kernel, kInt8FakeQuant };

struct AttnState {
  kernels::AttentionShape shape;
  float scale;
  int lk_pad;
  Scores scores;
  bool fast;         // the fp32 kernels (else the reference)
  size_t fq_floats;  // kInt8FakeQuant: Q and K fake-quantised at the scratch's start
  Split chunks;      // query rows per task, whole row groups, at most attn_max_rows
};

struct AttnTask {
  const OpNode* node;
  const RunContext* ctx;
  const float* q;
  const float* k;
  const float* v;
  float* scratch;  // past the fake-quantised Q and K, if any
};

void pack_task(void* data, int head, int) {
  const auto* t = static_cast<const AttnTask*>(data);
  const auto& s = t->node->state_as<AttnState>();
  const size_t e = size_t(s.shape.heads) * s.shape.head_dim;
  t->node->ks->attn_pack_kv(s.shape.kv_len, s.lk_pad, s.shape.head_dim, t->k, e, t->v, e, head,
                            t->scratch, t->scratch + e * s.lk_pad);
}

// A (head, query chunk) task: its head, first query row and row count.
struct BlockRows {
  int h, q0, rows;
};
BlockRows block_rows(const AttnState& s, int task) {
  const int c = task % s.chunks.tasks;
  return {task / s.chunks.tasks, s.chunks.begin(c), s.chunks.end(c) - s.chunks.begin(c)};
}

void block_task(void* data, int task, int thread) {
  const auto* t = static_cast<const AttnTask*>(data);
  const OpNode& node = *t->node;
  const auto& s = node.state_as<AttnState>();
  const size_t e = size_t(s.shape.heads) * s.shape.head_dim;
  const BlockRows b = block_rows(s, task);
  (void)node.ks->attn_block(b.rows, s.shape.kv_len, s.shape.head_dim, t->q, e, t->scratch,
                            t->scratch + e * s.lk_pad, s.lk_pad, s.scale, node.out[0]->f32(), e,
                            b.h, b.q0, t->ctx->thread_scratch[thread]);
}

// The int8 kernel's scratch: V packed (fp32, E * lk_pad floats), then K's int8 packing.
void q8_pack_task(void* data, int head, int) {
  const auto* t = static_cast<const AttnTask*>(data);
  const auto& s = t->node->state_as<AttnState>();
  const size_t e = size_t(s.shape.heads) * s.shape.head_dim;
  t->node->qks->attn_pack_kv(s.shape.kv_len, s.lk_pad, s.shape.head_dim, t->k, e, t->v, e, head,
                             reinterpret_cast<uint8_t*>(t->scratch + e * s.lk_pad), t->scratch);
}

void q8_block_task(void* data, int task, int thread) {
  const auto* t = static_cast<const AttnTask*>(data);
  const OpNode& node = *t->node;
  const auto& s = node.state_as<AttnState>();
  const size_t e = size_t(s.shape.heads) * s.shape.head_dim;
  const BlockRows b = block_rows(s, task);
  (void)node.qks->attn_block(b.rows, s.shape.kv_len, s.shape.head_dim, t->q, e,
                             reinterpret_cast<const uint8_t*>(t->scratch + e * s.lk_pad),
                             t->scratch, s.lk_pad, s.scale, node.out[0]->f32(), e, b.h, b.q0,
                             t->ctx->thread_scratch[thread]);
}

void eval_attention(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<AttnState>();
  AttnTask t{&node, &ctx, node.in[0]->f32(), node.in[1]->f32(), node.in[2]->f32(), ctx.scratch};
  if (s.scores == Scores::kInt8Kernel) {
    parallel_for(ctx, s.shape.heads, q8_pack_task, &t);
    parallel_for(ctx, s.shape.heads * s.chunks.tasks, q8_block_task, &t);
    return;
  }
  if (s.scores == Scores::kInt8FakeQuant) {
    const int e = s.shape.heads * s.shape.head_dim;
    float* qf = ctx.scratch;
    float* kf = qf + size_t(s.shape.q_len) * e;
    kernels::qs8_fake_quantize_rows(s.shape.q_len, s.shape.heads, s.shape.head_dim, t.q, size_t(e),
                                    qf);
    kernels::qs8_fake_quantize_rows(s.shape.kv_len, s.shape.heads, s.shape.head_dim, t.k, size_t(e),
                                    kf);
    t = {&node, &ctx, qf, kf, t.v, ctx.scratch + s.fq_floats};
  }
  if (!s.fast) {
    kernels::f32_attention__ref(s.shape, t.q, t.k, t.v, s.scale, node.out[0]->f32(), t.scratch);
    return;
  }
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
  const int32_t scores = node.params[2];
  APRT_OP_ENSURE(node, scores == 0 || scores == 1, Errc::kBadOp,
                 "scores precision %d unknown (0 fp32, 1 int8)", int(scores));
  auto& s = node.state_as<AttnState>();
  s.shape = {int(q->rows()), int(k->rows()), heads, e / heads};
  s.scale = scale;
  s.fq_floats = 0;
  node.flops = 4ull * q->rows() * k->rows() * e;
  node.eval = eval_attention;
  const int d = s.shape.head_dim;
  const kernels::QKernelSet* qks = node.qks;
  if (scores == 1 && node.ks && qks && qks->attn_block && d % 4 == 0 &&
      (d + node.ks->lanes - 1) / node.ks->lanes <= 8) {
    s.scores = Scores::kInt8Kernel;
    s.fast = true;
    const int step = qks->attn_key_block;
    s.lk_pad = (s.shape.kv_len + step - 1) / step * step;
    s.chunks = make_split(s.shape.q_len, qks->attn_group_rows,
                          (s.shape.q_len + qks->attn_max_rows - 1) / qks->attn_max_rows);
    node.scratch_floats =
        size_t(e) * s.lk_pad + (qks->attn_kq_bytes(heads, s.lk_pad, d) + 3) / 4;  // V, then K
    node.thread_scratch_floats = qks->attn_scratch(d);
    node.kernel = qks->isa;
    return ok();
  }
  s.scores = scores == 1 ? Scores::kInt8FakeQuant : Scores::kF32;
  if (scores == 1) s.fq_floats = (q->rows() + k->rows()) * size_t(e);
  s.fast = node.ks && (d + node.ks->lanes - 1) / node.ks->lanes <= 8;
  if (s.fast) {
    const int step = node.ks->attn_key_block;
    s.lk_pad = (s.shape.kv_len + step - 1) / step * step;
    const int max_rows = node.ks->attn_max_rows;
    s.chunks = make_split(s.shape.q_len, node.ks->attn_group_rows,
                          (s.shape.q_len + max_rows - 1) / max_rows);
    node.scratch_floats = s.fq_floats + 2 * size_t(e) * s.lk_pad;  // packed K^T and V
    node.thread_scratch_floats = node.ks->attn_scratch(d);
    node.kernel = node.ks->isa;
  } else {
    node.scratch_floats = s.fq_floats + kernels::f32_attention__ref_scratch(s.shape);
  }
  return ok();
}

}  // namespace aprt::ops
