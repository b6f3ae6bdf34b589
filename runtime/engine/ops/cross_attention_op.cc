// CROSS_ATTENTION_1Q: one query attending over memory rows whose key and value
// projections are folded away (see kernels/attention/f32_cross_attention_1q__ref.h).
// inputs: Q [1,E], M [L,E], P [L,E] or absent, Wk [E,E], bk [E], Wv [E,E], bv [E]
// params: heads, scale (f32 bits)
// Fast path, in the op's scratch: qt = scale W_k^T q per head (GEMM per head),
// scores s_h,j = qt_h . (m_j + p_j) in one pass over M and P (cross_scores),
// softmax per head, Z = A M, o_h = W_v,h z_h + b_v,h (Wv packed at load).
// Costs O(L E H) instead of the projections' O(L E^2).
#include <cstring>

#include "kernels/attention/f32_cross_attention_1q__ref.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

struct CrossState {
  int kv_len, heads, e;
  float scale;
  // Scratch layout (floats): qs [E] | qt [H][E] | s [H][L] | z [H][E]
  size_t off_qt, off_s, off_z;
  Split s_split;           // memory rows of the scores
  Split z_rows, z_panels;  // Z GEMM
};

const float* pos_of(const OpNode& node) {
  return node.in[2] ? node.in[2]->f32() : nullptr;
}

void eval_cross_ref(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<CrossState>();
  kernels::f32_cross_attention_1q__ref(s.kv_len, s.heads, s.e, node.in[0]->f32(), node.in[1]->f32(),
                                       pos_of(node), node.in[3]->f32(), node.in[5]->f32(),
                                       node.in[6]->f32(), s.scale, node.out[0]->f32(), ctx.scratch);
}

struct CrossTask {
  const OpNode* node;
  const RunContext* ctx;
  kernels::GemmArgs g;
  const Split* rows;
  const Split* panels;
};

void scores_task(void* data, int task, int) {
  const auto* t = static_cast<const CrossTask*>(data);
  const auto& s = t->node->state_as<CrossState>();
  float* base = t->ctx->scratch;
  t->node->ks->cross_scores(s.e, s.heads, t->node->in[1]->f32(), pos_of(*t->node), base + s.off_qt,
                            base + s.off_s, size_t(s.kv_len), s.s_split.begin(task),
                            s.s_split.end(task));
}

void gemm_task(void* data, int task, int) {
  const auto* t = static_cast<const CrossTask*>(data);
  const int rt = task % t->rows->tasks, pt = task / t->rows->tasks;
  t->node->ks->gemm(t->g, t->rows->begin(rt), t->rows->end(rt), t->panels->begin(pt),
                    t->panels->end(pt));
}

// qt_h = (scale q_h) W_k,h for head `task`: A = [1][d], B = rows h*d.. of Wk
// as a row-major [d][E]. One head per task: these single-row products are
// bound by streaming the weights, which two cores do faster than one.
void qt_task(void* data, int h, int) {
  const auto* t = static_cast<const CrossTask*>(data);
  const OpNode& node = *t->node;
  const auto& s = node.state_as<CrossState>();
  const int e = s.e, d = e / s.heads;
  const size_t nr = size_t(node.ks->gemm_nr);
  float* qs = t->ctx->scratch;
  const kernels::GemmArgs g{1,
                            e,
                            d,
                            qs + h * d,
                            size_t(d),
                            node.in[3]->f32() + size_t(h) * d * e,
                            size_t(e),
                            nr,
                            false,
                            nullptr,
                            nullptr,
                            0,
                            t->ctx->scratch + s.off_qt + size_t(h) * e,
                            size_t(e),
                            kernels::Act::kNone};
  node.ks->gemm(g, 0, 1, 0, int((size_t(e) + nr - 1) / nr));
}

// o_h = z_h W_v,h^T + b_v,h over the packed Wv panels of head `task`.
void out_task(void* data, int h, int) {
  const auto* t = static_cast<const CrossTask*>(data);
  const OpNode& node = *t->node;
  const auto& s = node.state_as<CrossState>();
  const int e = s.e, d = e / s.heads;
  const size_t nr = size_t(node.ks->gemm_nr);
  const int panels_per_head = d / node.ks->gemm_nr;
  const kernels::GemmArgs g{1,
                            e,
                            e,
                            t->ctx->scratch + s.off_z + size_t(h) * e,
                            size_t(e),
                            node.packed,
                            nr,
                            size_t(e) * nr,
                            true,
                            node.in[6]->f32(),
                            nullptr,
                            0,
                            node.out[0]->f32(),
                            size_t(e),
                            kernels::Act::kNone};
  node.ks->gemm(g, 0, 1, h * panels_per_head, (h + 1) * panels_per_head);
}

void eval_cross_fast(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<CrossState>();
  const kernels::KernelSet& ks = *node.ks;
  const int e = s.e, h_count = s.heads, l = s.kv_len;
  const size_t nr = size_t(ks.gemm_nr);
  float* base = ctx.scratch;
  float* qs = base;
  float* sm = base + s.off_s;
  float* z = base + s.off_z;
  const float* q = node.in[0]->f32();
  for (int c = 0; c < e; ++c) qs[c] = q[c] * s.scale;
  CrossTask heads{&node, &ctx, {}, nullptr, nullptr};
  parallel_for(ctx, h_count, qt_task, &heads);
  // s [H][L]: qt_h . (m_j + p_j)
  parallel_for(ctx, s.s_split.tasks, scores_task, &heads);
  ks.softmax_rows(l, sm, 0, h_count);
  {  // Z [H][E] = A [H][L] x M [L][E]
    CrossTask t{&node,
                &ctx,
                {h_count, e, l, sm, size_t(l), node.in[1]->f32(), size_t(e), nr, false, nullptr,
                 nullptr, 0, z, size_t(e), kernels::Act::kNone},
                &s.z_rows,
                &s.z_panels};
    parallel_for(ctx, s.z_rows.tasks * s.z_panels.tasks, gemm_task, &t);
  }
  parallel_for(ctx, h_count, out_task, &heads);
}

void pack_wv(OpNode& node) {
  const auto& s = node.state_as<CrossState>();
  kernels::f32_pack_b(s.e, s.e, node.ks->gemm_nr, node.in[5]->f32(), node.packed);
}

}  // namespace

Status prepare_cross_attention_1q(OpNode& node) {
  Status st;
  const Tensor* q = node.in[0];
  const Tensor* m = node.in[1];
  const Tensor* y = node.out[0];
  APRT_OP_ENSURE(node, node.n_in == 7, Errc::kBadOp, "needs 7 inputs, has %d", node.n_in);
  APRT_OP_ENSURE(node, q && q->dtype == format::DType::kF32, Errc::kShapeMismatch,
                 "query must be f32");
  if (!(st = expect_f32(node, m, "memory", false))) return st;
  if (!(st = expect_f32(node, y, "output", false))) return st;
  const int e = q->last_dim();
  APRT_OP_ENSURE(node, q->numel == size_t(e), Errc::kShapeMismatch, "query must be one row");
  APRT_OP_ENSURE(node, m->last_dim() == e, Errc::kShapeMismatch,
                 "memory width %d differs from the query's %d", m->last_dim(), e);
  if (node.in[2]) {
    APRT_OP_ENSURE(node, node.in[2]->dtype == format::DType::kF32 && node.in[2]->numel == m->numel,
                   Errc::kShapeMismatch, "positions must be f32 and shaped like the memory");
  }
  const int wd[2] = {e, e}, bd[1] = {e};
  const char* roles[4] = {"key weights", "key bias", "value weights", "value bias"};
  for (int i = 3; i < 7; ++i) {
    if (!(st = expect_f32(node, node.in[i], roles[i - 3], true))) return st;
    if (!(st = expect_dims(node, node.in[i], roles[i - 3], (i % 2) ? 2 : 1, (i % 2) ? wd : bd))) {
      return st;
    }
  }
  APRT_OP_ENSURE(node, y->numel == size_t(e), Errc::kShapeMismatch, "output must be one row");
  const int heads = node.params[0];
  const float scale = param_f32(node, 1);
  APRT_OP_ENSURE(node, heads >= 1 && e % heads == 0, Errc::kBadOp,
                 "%d heads do not divide the width %d", heads, e);
  APRT_OP_ENSURE(node, std::isfinite(scale) && scale > 0.0f, Errc::kBadOp, "scale %g invalid",
                 scale);
  auto& s = node.state_as<CrossState>();
  s.kv_len = int(m->rows());
  s.heads = heads;
  s.e = e;
  s.scale = scale;
  const size_t l = size_t(s.kv_len), h = size_t(heads), ee = size_t(e);
  node.flops = 2ull * (ee * ee + l * ee * (h + h) + ee * ee);
  const bool fast = node.ks && (e / heads) % node.ks->gemm_nr == 0;
  if (fast) {
    s.off_qt = ee;
    s.off_s = s.off_qt + h * ee;
    s.off_z = s.off_s + l * h;
    node.scratch_floats = s.off_z + h * ee;
    const int threads = node.threads;
    s.s_split = make_split(s.kv_len, 1, threads <= 1 ? 1 : 2 * threads);
    split_gemm(heads, e, s.kv_len, node.ks->gemm_mr, node.ks->gemm_nr, threads, &s.z_rows,
               &s.z_panels);
    node.packed_floats = kernels::f32_pack_b_floats(e, e, node.ks->gemm_nr);
    node.pack = pack_wv;
    node.packed_inputs = 1u << 5;
    node.packed_layout = "f32 GEMM weight panels [n/nr][k][nr]";
    node.packed_tile = node.ks->gemm_nr;
    node.eval = eval_cross_fast;
    node.kernel = node.ks->isa;
  } else {
    node.scratch_floats = kernels::f32_cross_attention_1q__ref_scratch(s.kv_len, e);
    node.eval = eval_cross_ref;
  }
  return ok();
}

}  // namespace aprt::ops
