// ATTENTION: multi-head softmax(scale Q K^T) V over row-major Q [Lq,E], K/V [Lk,E].
// params: heads, scale (f32 bits), precision (0 fp32; 1 int8 scores:
// kernels/attention/qs8_attention.h; 2 bf16: kernels/attention/bf16_attention__ref.h)
// Fast path: K and V are packed per head into the op's scratch (K^T in key
// blocks; tasks over heads), then (head, query chunk) tasks run the fused
// online-softmax kernel. int8 scores: the int8 table's kernel where it has one
// (AVX-512 VNNI), else Q and K fake-quantised into scratch and the fp32 path
// over them -- the same scores up to the rounding of fp32 products of small
// integers. bf16: the bf16 table's kernel where the CPU has one (AVX-512
// BF16), else Q, K and V rounded to bf16 into scratch and the fp32 path over
// them (the weights unrounded), or the bf16 reference without fast kernels.
#include "kernels/attention/bf16_attention__ref.h"
#include "kernels/attention/f32_attention__ref.h"
#include "kernels/attention/qs8_attention__ref.h"
#include "kernels/gemm/qs8_gemm.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

enum class Scores : uint8_t { kF32, kInt8Kernel, kInt8FakeQuant, kBf16Kernel, kBf16Rounded };

struct AttnState {
  kernels::AttentionShape shape;
  float scale;
  int lk_pad;
  Scores scores;
  bool fast;         // the fp32 kernels (else the reference)
  size_t fq_floats;  // kInt8FakeQuant, kBf16Rounded: Q and K (and V) at the scratch's start
  Split chunks;      // query rows per task, whole row groups, at most attn_max_rows
  Split prep;        // kInt8FakeQuant, kBf16Rounded: rows of Q, K (, V) per preparation task
};

struct AttnTask {
  const OpNode* node;
  const RunContext* ctx;
  const float* q;
  const float* k;
  const float* v;
  float* scratch;  // past the fake-quantised Q and K, if any
};

// What every task reads first: its data, the node, the op's state and E.
struct TaskView {
  const AttnTask& t;
  const OpNode& node;
  const AttnState& s;
  size_t e;
  explicit TaskView(void* data)
      : t(*static_cast<const AttnTask*>(data)),
        node(*t.node),
        s(node.state_as<AttnState>()),
        e(size_t(s.shape.heads) * s.shape.head_dim) {}
};

void pack_task(void* data, int head, int) {
  const TaskView v(data);
  v.node.ks->attn_pack_kv(v.s.shape.kv_len, v.s.lk_pad, v.s.shape.head_dim, v.t.k, v.e, v.t.v, v.e,
                          head, v.t.scratch, v.t.scratch + v.e * v.s.lk_pad);
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
  const TaskView v(data);
  const BlockRows b = block_rows(v.s, task);
  (void)v.node.ks->attn_block(b.rows, v.s.shape.kv_len, v.s.shape.head_dim, v.t.q, v.e, v.t.scratch,
                              v.t.scratch + v.e * v.s.lk_pad, v.s.lk_pad, v.s.scale,
                              v.node.out[0]->f32(), v.e, b.h, b.q0,
                              v.t.ctx->thread_scratch[thread]);
}

// The int8 kernel's scratch: V packed (fp32, E * lk_pad floats), then K's int8 packing.
void q8_pack_task(void* data, int head, int) {
  const TaskView v(data);
  v.node.qks->attn_pack_kv(v.s.shape.kv_len, v.s.lk_pad, v.s.shape.head_dim, v.t.k, v.e, v.t.v, v.e,
                           head, reinterpret_cast<uint8_t*>(v.t.scratch + v.e * v.s.lk_pad),
                           v.t.scratch);
}

void q8_block_task(void* data, int task, int thread) {
  const TaskView v(data);
  const BlockRows b = block_rows(v.s, task);
  (void)v.node.qks->attn_block(b.rows, v.s.shape.kv_len, v.s.shape.head_dim, v.t.q, v.e,
                               reinterpret_cast<const uint8_t*>(v.t.scratch + v.e * v.s.lk_pad),
                               v.t.scratch, v.s.lk_pad, v.s.scale, v.node.out[0]->f32(), v.e, b.h,
                               b.q0, v.t.ctx->thread_scratch[thread]);
}

// The bf16 kernel's scratch: K and V of all heads packed as bf16.
void bf16_pack_task(void* data, int head, int) {
  const TaskView v(data);
  v.node.bks->pack_kv(v.s.shape.kv_len, v.s.lk_pad, v.s.shape.head_dim, v.t.k, v.e, v.t.v, v.e,
                      head, reinterpret_cast<uint16_t*>(v.t.scratch));
}

void bf16_block_task(void* data, int task, int thread) {
  const TaskView v(data);
  const BlockRows b = block_rows(v.s, task);
  (void)v.node.bks->block(b.rows, v.s.shape.kv_len, v.s.shape.head_dim, v.t.q, v.e,
                          reinterpret_cast<const uint16_t*>(v.t.scratch), v.s.lk_pad, v.s.scale,
                          v.node.out[0]->f32(), v.e, b.h, b.q0, v.t.ctx->thread_scratch[thread]);
}

// The fallback paths' preparation in row tasks over Q, K (and V) stacked:
// each row rounded to bf16, or fake-quantised per head, into the scratch's
// start (row-local arithmetic: any split gives the same values).
struct PrepTask {
  const AttnState* s;
  int n;  // matrices: Q, K (, V)
  const float* src[3];
  float* dst[3];
  int rows[3];
};

void prep_task(void* data, int task, int) {
  const auto* p = static_cast<const PrepTask*>(data);
  const AttnState& s = *p->s;
  const int e = s.shape.heads * s.shape.head_dim;
  int r0 = s.prep.begin(task), r1 = s.prep.end(task);
  for (int m = 0; m < p->n; ++m) {
    const int a = r0 > 0 ? r0 : 0, b = r1 < p->rows[m] ? r1 : p->rows[m];
    if (a < b) {
      const float* x = p->src[m] + size_t(a) * e;
      float* y = p->dst[m] + size_t(a) * e;
      if (s.scores == Scores::kBf16Rounded) {
        kernels::bf16_round_rows(b - a, e, x, size_t(e), y);
      } else {
        kernels::qs8_fake_quantize_rows(b - a, s.shape.heads, s.shape.head_dim, x, size_t(e), y);
      }
    }
    r0 -= p->rows[m];
    r1 -= p->rows[m];
  }
}

void eval_attention(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<AttnState>();
  AttnTask t{&node, &ctx, node.in[0]->f32(), node.in[1]->f32(), node.in[2]->f32(), ctx.scratch};
  if (s.scores == Scores::kBf16Kernel) {
    parallel_for(ctx, s.shape.heads, bf16_pack_task, &t);
    parallel_for(ctx, s.shape.heads * s.chunks.tasks, bf16_block_task, &t);
    return;
  }
  if (s.scores == Scores::kBf16Rounded) {
    if (!s.fast) {
      kernels::bf16_attention__ref(s.shape, t.q, t.k, t.v, s.scale, node.out[0]->f32(),
                                   ctx.scratch);
      return;
    }
    const int e = s.shape.heads * s.shape.head_dim;
    float* qb = ctx.scratch;
    float* kb = qb + size_t(s.shape.q_len) * e;
    float* vb = kb + size_t(s.shape.kv_len) * e;
    PrepTask p{
        &s, 3, {t.q, t.k, t.v}, {qb, kb, vb}, {s.shape.q_len, s.shape.kv_len, s.shape.kv_len}};
    parallel_for(ctx, s.prep.tasks, prep_task, &p);
    t = {&node, &ctx, qb, kb, vb, ctx.scratch + s.fq_floats};
  }
  if (s.scores == Scores::kInt8Kernel) {
    parallel_for(ctx, s.shape.heads, q8_pack_task, &t);
    parallel_for(ctx, s.shape.heads * s.chunks.tasks, q8_block_task, &t);
    return;
  }
  if (s.scores == Scores::kInt8FakeQuant) {
    const int e = s.shape.heads * s.shape.head_dim;
    float* qf = ctx.scratch;
    float* kf = qf + size_t(s.shape.q_len) * e;
    PrepTask p{&s, 2, {t.q, t.k, nullptr}, {qf, kf, nullptr}, {s.shape.q_len, s.shape.kv_len, 0}};
    parallel_for(ctx, s.prep.tasks, prep_task, &p);
    t = {&node, &ctx, qf, kf, t.v, ctx.scratch + s.fq_floats};
  }
  if (!s.fast) {
    kernels::f32_attention__ref(s.shape, t.q, t.k, t.v, s.scale, node.out[0]->f32(), t.scratch);
    return;
  }
  parallel_for(ctx, s.shape.heads, pack_task, &t);
  parallel_for(ctx, s.shape.heads * s.chunks.tasks, block_task, &t);
}

// The fused kernels' blocking, whichever table runs: keys padded to whole key
// blocks, query rows split into chunks of whole row groups, at most max_rows.
void plan_blocks(AttnState& s, int key_block, int group_rows, int max_rows) {
  s.lk_pad = (s.shape.kv_len + key_block - 1) / key_block * key_block;
  s.chunks = make_split(s.shape.q_len, group_rows, (s.shape.q_len + max_rows - 1) / max_rows);
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
  APRT_OP_ENSURE(node, scores >= 0 && scores <= 2, Errc::kBadOp,
                 "precision %d unknown (0 fp32, 1 int8 scores, 2 bf16)", int(scores));
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
    plan_blocks(s, qks->attn_key_block, qks->attn_group_rows, qks->attn_max_rows);
    node.scratch_floats =
        size_t(e) * s.lk_pad + (qks->attn_kq_bytes(heads, s.lk_pad, d) + 3) / 4;  // V, then K
    node.thread_scratch_floats = qks->attn_scratch(d);
    node.kernel = qks->isa;
    return ok();
  }
  const kernels::Bf16AttentionKernels* bks = node.bks;
  if (scores == 2 && bks && d % 2 == 0 && d <= 128) {
    s.scores = Scores::kBf16Kernel;
    s.fast = true;
    plan_blocks(s, bks->key_block, bks->group_rows, bks->max_rows);
    node.scratch_floats = (bks->kv_bytes(heads, s.lk_pad, d) + 3) / 4;
    node.thread_scratch_floats = bks->scratch(d);
    node.kernel = bks->isa;
    return ok();
  }
  s.scores = scores == 1   ? Scores::kInt8FakeQuant
             : scores == 2 ? Scores::kBf16Rounded
                           : Scores::kF32;
  if (scores == 1) s.fq_floats = (q->rows() + k->rows()) * size_t(e);
  if (scores == 2) s.fq_floats = (q->rows() + 2 * k->rows()) * size_t(e);
  s.prep = make_split(int(q->rows() + (scores == 2 ? 2 : 1) * k->rows()), 16, node.threads);
  s.fast = node.ks && (d + node.ks->lanes - 1) / node.ks->lanes <= 8;
  if (s.fast) {
    plan_blocks(s, node.ks->attn_key_block, node.ks->attn_group_rows, node.ks->attn_max_rows);
    node.scratch_floats = s.fq_floats + 2 * size_t(e) * s.lk_pad;  // packed K^T and V
    node.thread_scratch_floats = node.ks->attn_scratch(d);
    node.kernel = node.ks->isa;
  } else if (scores == 2) {
    node.scratch_floats = kernels::bf16_attention__ref_scratch(s.shape);
  } else {
    node.scratch_floats = s.fq_floats + kernels::f32_attention__ref_scratch(s.shape);
  }
  return ok();
}

}  // namespace aprt::ops
