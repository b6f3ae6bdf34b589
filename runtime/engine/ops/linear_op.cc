// LINEAR: Y[M,N] = act(X[M,K] W[N,K]^T + B[N]) + R[M,N]. Rows are every axis but the last.
// inputs: X, W, B, R?   params: act
#include "kernels/ref/f32_linear__ref.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

struct LinearState {
  kernels::GemmShape shape;
  kernels::Act act;
};

void eval_linear_ref(const OpNode& node, const RunContext&) {
  const auto& s = node.state_as<LinearState>();
  const float* residual = node.n_in > 3 && node.in[3] ? node.in[3]->f32() : nullptr;
  kernels::f32_linear__ref(s.shape, node.in[0]->f32(), node.in[1]->f32(), node.in[2]->f32(),
                           residual, s.act, node.out[0]->f32());
}

}  // namespace

Status prepare_linear(OpNode& node) {
  const Tensor* x = node.in[0];
  const Tensor* w = node.in[1];
  const Tensor* b = node.in[2];
  const Tensor* y = node.out[0];
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
  node.eval = eval_linear_ref;
  return ok();
}

}  // namespace aprt::ops
