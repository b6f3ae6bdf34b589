// CROSS_ATTENTION_1Q: one query attending over memory rows whose key and value
// projections are folded away (see kernels/ref/f32_cross_attention_1q__ref.h).
// inputs: Q [1,E], M [L,E], P [L,E] or absent, Wk [E,E], bk [E], Wv [E,E], bv [E]
// params: heads, scale (f32 bits)
// Fast path, in the op's scratch: qt = scale W_k^T q per head (GEMM per head),
// X = M + P, scores^T = X qt^T, softmax per head, Z = A M, o_h = W_v,h z_h + b_v,h
// (Wv packed at load). Costs O(L E H) instead of the projections' O(L E^2).
#include <cstring>

#include "kernels/ref/f32_cross_attention_1q__ref.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

struct CrossState {
  int kv_len, heads, e;
  float scale;
  // Scratch layout (floats): qs [E] | qt [H][E] | qtT [E][H] | X [L][E] | sT [L][H] | s [H][L] | z
  // [H][E]
  size_t off_qt, off_qtt, off_x, off_st, off_s, off_z;
  Split x_split;           // elements of X = M + P
  Split s_rows, s_panels;  // scores^T GEMM
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

void add_task(void* data, int task, int) {
  const auto* t = static_cast<const CrossTask*>(data);
  const auto& s = t->node->state_as<CrossState>();
  t->node->ks->add(t->node->in[1]->f32(), pos_of(*t->node), t->ctx->scratch + s.off_x,
                   size_t(s.x_split.begin(task)), size_t(s.x_split.end(task)));
}

void gemm_task(void* data, int task, int) {
  const auto* t = static_cast<const CrossTask*>(data);
  const int rt = task % t->rows->tasks, pt = task / t->rows->tasks;
  t->node->ks->gemm(t->g, t->rows->begin(rt), t->rows->end(rt), t->panels->begin(pt),
                    t->panels->end(pt));
}

void eval_cross_fast(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<CrossState>();
  const kernels::KernelSet& ks = *node.ks;
  const int e = s.e, h_count = s.heads, d = e / h_count, l = s.kv_len;
  const size_t nr = size_t(ks.gemm_nr);
  float* base = ctx.scratch;
  float* qs = base;
  float* qt = base + s.off_qt;
  float* qtt = base + s.off_qtt;
  float* st = base + s.off_st;
  float* sm = base + s.off_s;
  float* z = base + s.off_z;
  const float* q = node.in[0]->f32();
  for (int c = 0; c < e; ++c) qs[c] = q[c] * s.scale;
  // qt_h = (scale q_h) W_k,h: A = [1][d], B = rows h*d.. of Wk as a row-major [d][E].
  for (int h = 0; h < h_count; ++h) {
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
                              qt + size_t(h) * e,
                              size_t(e),
                              kernels::Act::kNone};
    ks.gemm(g, 0, 1, 0, int((size_t(e) + nr - 1) / nr));
  }
  for (int h = 0; h < h_count; ++h) {
    for (int c = 0; c < e; ++c) qtt[size_t(c) * h_count + h] = qt[size_t(h) * e + c];
  }
  const float* keys = node.in[1]->f32();
  if (pos_of(node)) {
    CrossTask t{&node, &ctx, {}, nullptr, nullptr};
    parallel_for(ctx, s.x_split.tasks, add_task, &t);
    keys = base + s.off_x;
  }
  {  // scores^T [L][H] = keys [L][E] x qt^T [E][H]
    CrossTask t{&node,
                &ctx,
                {l, h_count, e, keys, size_t(e), qtt, size_t(h_count), nr, false, nullptr, nullptr,
                 0, st, size_t(h_count), kernels::Act::kNone},
                &s.s_rows,
                &s.s_panels};
    parallel_for(ctx, s.s_rows.tasks * s.s_panels.tasks, gemm_task, &t);
  }
  for (int j = 0; j < l; ++j) {
    for (int h = 0; h < h_count; ++h) sm[size_t(h) * l + j] = st[size_t(j) * h_count + h];
  }
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
  // o_h = z_h W_v,h^T + b_v,h over the packed Wv panels of head h.
  float* o = node.out[0]->f32();
  const int panels_per_head = d / ks.gemm_nr;
  for (int h = 0; h < h_count; ++h) {
    const kernels::GemmArgs g{1,
                              e,
                              e,
                              z + size_t(h) * e,
                              size_t(e),
                              node.packed,
                              nr,
                              size_t(e) * nr,
                              true,
                              node.in[6]->f32(),
                              nullptr,
                              0,
                              o,
                              size_t(e),
                              kernels::Act::kNone};
    ks.gemm(g, 0, 1, h * panels_per_head, (h + 1) * panels_per_head);
  }
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
    s.off_qtt = s.off_qt + h * ee;
    s.off_x = s.off_qtt + h * ee;
    s.off_st = s.off_x + (node.in[2] ? l * ee : 0);
    s.off_s = s.off_st + l * h;
    s.off_z = s.off_s + l * h;
    node.scratch_floats = s.off_z + h * ee;
    const int threads = node.threads;
    int tasks = threads <= 1 ? 1 : 2 * threads;
    s.x_split = make_split(int(l * ee), 64, tasks);
    split_gemm(s.kv_len, heads, e, node.ks->gemm_mr, node.ks->gemm_nr, threads, &s.s_rows,
               &s.s_panels);
    split_gemm(heads, e, s.kv_len, node.ks->gemm_mr, node.ks->gemm_nr, threads, &s.z_rows,
               &s.z_panels);
    node.packed_floats = kernels::f32_pack_b_floats(e, e, node.ks->gemm_nr);
    node.pack = pack_wv;
    node.eval = eval_cross_fast;
    node.kernel = node.ks->isa;
  } else {
    node.scratch_floats = kernels::f32_cross_attention_1q__ref_scratch(s.kv_len, e);
    node.eval = eval_cross_ref;
  }
  return ok();
}

}  // namespace aprt::ops
