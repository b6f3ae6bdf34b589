// LINEAR: Y[M,N] = act(X[M,K] W[N,K]^T + B[N]) + R[M,N]. Rows are every axis but the last.
// inputs: X, W, B, R?   params: act
// Fast path: W packed at load into the kernel's column panels; the output is
// split into a grid of row groups x panel groups across threads.
#include "kernels/gemm/f32_gemm__ref.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

struct LinearState {
  kernels::GemmShape shape;
  kernels::Act act;
  Split rows;    // in rows, whole tiles
  Split panels;  // in panels
};

void eval_linear_ref(const OpNode& node, const RunContext&) {
  const auto& s = node.state_as<LinearState>();
  const float* residual = node.n_in > 3 && node.in[3] ? node.in[3]->f32() : nullptr;
  kernels::f32_gemm__ref(s.shape, node.in[0]->f32(), node.in[1]->f32(), node.in[2]->f32(), residual,
                         s.act, node.out[0]->f32());
}

struct LinearTask {
  const OpNode* node;
  kernels::GemmArgs args;
};

void linear_task(void* data, int task, int) {
  const auto* t = static_cast<const LinearTask*>(data);
  const auto& s = t->node->state_as<LinearState>();
  const int rt = task % s.rows.tasks, pt = task / s.rows.tasks;
  t->node->ks->gemm(t->args, s.rows.begin(rt), s.rows.end(rt), s.panels.begin(pt),
                    s.panels.end(pt));
}

void eval_linear_fast(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<LinearState>();
  const int nr = node.ks->gemm_nr;
  const float* residual = node.n_in > 3 && node.in[3] ? node.in[3]->f32() : nullptr;
  LinearTask t{&node,
               {s.shape.m, s.shape.n, s.shape.k, node.in[0]->f32(), size_t(s.shape.k), node.packed,
                size_t(nr), size_t(s.shape.k) * nr, true, node.in[2]->f32(), residual,
                size_t(s.shape.n), node.out[0]->f32(), size_t(s.shape.n), s.act}};
  parallel_for(ctx, s.rows.tasks * s.panels.tasks, linear_task, &t);
}

void pack_linear(OpNode& node) {
  const auto& s = node.state_as<LinearState>();
  kernels::f32_pack_b(s.shape.n, s.shape.k, node.ks->gemm_nr, node.in[1]->f32(), node.packed);
}

}  // namespace

void split_gemm(int m, int n, int k, int mr, int nr, int threads, Split* rows, Split* panels) {
  const int panel_count = (n + nr - 1) / nr;
  const long long work = static_cast<long long>(m) * n * k;
  int want = threads <= 1 ? 1 : int(work / 65536);
  // A product of a few rows is bound by streaming its weights (the decoders'
  // single-token layers: 256 KB each, cold every frame): split its panels so
  // that every core pulls its share.
  if (threads > 1 && want < threads && static_cast<long long>(n) * k >= 32768 &&
      panel_count >= threads) {
    want = threads;
  }
  want = want < 1 ? 1 : (want > 4 * threads ? 4 * threads : want);
  const int row_tiles = (m + mr - 1) / mr;
  if (row_tiles >= want) {
    *rows = make_split(m, mr, want);
    *panels = make_split(panel_count, 1, 1);
  } else {
    *rows = make_split(m, mr, row_tiles);
    *panels = make_split(panel_count, 1, (want + rows->tasks - 1) / rows->tasks);
  }
}

Status prepare_linear(OpNode& node) {
  const Tensor* x = node.in[0];
  const Tensor* w = node.in[1];
  const Tensor* b = node.in[2];
  const Tensor* y = node.out[0];
  if (w && w->dtype == format::DType::kI8) return prepare_qlinear(node);
  Status st;
  if (!(st = expect_f32(node, x, "input", false))) return st;
  if (!(st = expect_f32(node, w, "weights", true))) return st;
  if (!(st = expect_f32(node, b, "bias", true))) return st;
  if (!(st = expect_f32(node, y, "output", false))) return st;
  if (!(st = expect_act(node, node.params[0]))) return st;
  APRT_OP_ENSURE(node, w->rank == 2, Errc::kShapeMismatch, "weights '%s' must be [N, K]", w->name);
  const int n = w->dims[0], k = w->dims[1];
  const int bd[1] = {n};
  if (!(st = expect_dims(node, b, "bias", 1, bd))) return st;
  APRT_OP_ENSURE(node, x->last_dim() == k, Errc::kShapeMismatch,
                 "input '%s' rows have %d values, weights expect %d", x->name, x->last_dim(), k);
  APRT_OP_ENSURE(node, y->last_dim() == n && y->numel == x->rows() * size_t(n),
                 Errc::kShapeMismatch, "output '%s' must be %zu x %d", y->name, x->rows(), n);
  if (node.n_in > 3 && node.in[3]) {
    if (!(st = expect_f32(node, node.in[3], "residual", false))) return st;
    APRT_OP_ENSURE(node, node.in[3]->numel == y->numel, Errc::kShapeMismatch,
                   "residual has %zu elements, output %zu", node.in[3]->numel, y->numel);
  }
  auto& s = node.state_as<LinearState>();
  s.shape = {int(x->rows()), n, k};
  s.act = static_cast<kernels::Act>(node.params[0]);
  node.flops = 2ull * x->rows() * n * k;
  if (node.ks) {
    split_gemm(s.shape.m, n, k, node.ks->gemm_mr, node.ks->gemm_nr, node.threads, &s.rows,
               &s.panels);
    node.packed_floats = kernels::f32_pack_b_floats(n, k, node.ks->gemm_nr);
    node.pack = pack_linear;
    node.packed_inputs = 1u << 1;
    node.packed_layout = "f32 GEMM weight panels [n/nr][k][nr]";
    node.packed_tile = node.ks->gemm_nr;
    node.eval = eval_linear_fast;
    node.kernel = node.ks->isa;
  } else {
    node.eval = eval_linear_ref;
  }
  return ok();
}

}  // namespace aprt::ops
