// LAYERNORM over the last axis. inputs: X, gamma [N], beta [N]; params: eps (f32 bits)
#include "kernels/rowwise/f32_layernorm__ref.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

struct LnState {
  int rows, n;
  float eps;
  Split split;
};

void eval_layernorm_ref(const OpNode& node, const RunContext&) {
  const auto& s = node.state_as<LnState>();
  kernels::f32_layernorm__ref(s.rows, s.n, node.in[0]->f32(), node.in[1]->f32(), node.in[2]->f32(),
                              s.eps, node.out[0]->f32());
}

void ln_task(void* data, int task, int) {
  const auto& node = *static_cast<const OpNode*>(data);
  const auto& s = node.state_as<LnState>();
  node.ks->layernorm_rows(s.n, node.in[0]->f32(), node.in[1]->f32(), node.in[2]->f32(), s.eps,
                          node.out[0]->f32(), s.split.begin(task), s.split.end(task));
}

void eval_layernorm_fast(const OpNode& node, const RunContext& ctx) {
  parallel_for(ctx, node.state_as<LnState>().split.tasks, ln_task, const_cast<OpNode*>(&node));
}

}  // namespace

Status prepare_layernorm(OpNode& node) {
  const Tensor* x = node.in[0];
  const Tensor* y = node.out[0];
  Status st;
  if (!(st = expect_f32(node, x, "input", false))) return st;
  if (!(st = expect_f32(node, node.in[1], "gamma", true))) return st;
  if (!(st = expect_f32(node, node.in[2], "beta", true))) return st;
  if (!(st = expect_f32(node, y, "output", false))) return st;
  const int n = x->last_dim();
  const int nd[1] = {n};
  if (!(st = expect_dims(node, node.in[1], "gamma", 1, nd))) return st;
  if (!(st = expect_dims(node, node.in[2], "beta", 1, nd))) return st;
  APRT_OP_ENSURE(node, y->numel == x->numel && y->last_dim() == n, Errc::kShapeMismatch,
                 "output shape differs from the input's");
  const float eps = param_f32(node, 0);
  APRT_OP_ENSURE(node, std::isfinite(eps) && eps > 0.0f && eps < 1.0f, Errc::kBadOp,
                 "epsilon %g outside (0, 1)", eps);
  auto& s = node.state_as<LnState>();
  s.rows = int(x->rows());
  s.n = n;
  s.eps = eps;
  node.flops = 8ull * x->numel;
  if (node.ks) {
    const int min_rows = 16384 / n + 1;
    int tasks = node.threads <= 1 ? 1 : 2 * node.threads;
    if (tasks > s.rows / min_rows) tasks = s.rows / min_rows;
    s.split = make_split(s.rows, 1, tasks < 1 ? 1 : tasks);
    node.eval = eval_layernorm_fast;
    node.kernel = node.ks->isa;
  } else {
    node.eval = eval_layernorm_ref;
  }
  return ok();
}

}  // namespace aprt::ops
