// ADD (a + b, same element count), ACTIVATION (params: act) and CONCAT (row-wise).
#include "kernels/ref/f32_elementwise__ref.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

struct ActState {
  kernels::Act act;
};

struct ConcatState {
  int rows;
  int widths[format::kMaxOpInputs];
};

void eval_add_ref(const OpNode& node, const RunContext&) {
  kernels::f32_add__ref(node.out[0]->numel, node.in[0]->f32(), node.in[1]->f32(),
                        node.out[0]->f32());
}

void eval_activation_ref(const OpNode& node, const RunContext&) {
  kernels::f32_activation__ref(node.out[0]->numel, node.state_as<ActState>().act, node.in[0]->f32(),
                               node.out[0]->f32());
}

void eval_concat_ref(const OpNode& node, const RunContext&) {
  const auto& s = node.state_as<ConcatState>();
  const float* xs[format::kMaxOpInputs];
  for (int i = 0; i < node.n_in; ++i) xs[i] = node.in[i]->f32();
  kernels::f32_concat_rows__ref(s.rows, node.n_in, xs, s.widths, node.out[0]->f32());
}

}  // namespace

Status prepare_add(OpNode& node) {
  Status st;
  APRT_OP_ENSURE(node, node.n_in == 2, Errc::kBadOp, "needs 2 inputs, has %d", node.n_in);
  if (!(st = expect_f32(node, node.in[0], "first operand", false))) return st;
  APRT_OP_ENSURE(node, node.in[1] && node.in[1]->dtype == format::DType::kF32, Errc::kShapeMismatch,
                 "second operand must be f32");
  if (!(st = expect_f32(node, node.out[0], "output", false))) return st;
  APRT_OP_ENSURE(node,
                 node.in[0]->numel == node.in[1]->numel && node.out[0]->numel == node.in[0]->numel,
                 Errc::kShapeMismatch, "operands/output have %zu, %zu and %zu elements",
                 node.in[0]->numel, node.in[1]->numel, node.out[0]->numel);
  node.flops = node.out[0]->numel;
  node.eval = eval_add_ref;
  return ok();
}

Status prepare_activation(OpNode& node) {
  Status st;
  if (!(st = expect_f32(node, node.in[0], "input", false))) return st;
  if (!(st = expect_f32(node, node.out[0], "output", false))) return st;
  if (!(st = expect_act(node, node.params[0]))) return st;
  APRT_OP_ENSURE(node, node.in[0]->numel == node.out[0]->numel, Errc::kShapeMismatch,
                 "input has %zu elements, output %zu", node.in[0]->numel, node.out[0]->numel);
  node.state_as<ActState>().act = static_cast<kernels::Act>(node.params[0]);
  node.flops = node.out[0]->numel;
  node.eval = eval_activation_ref;
  return ok();
}

Status prepare_concat(OpNode& node) {
  Status st;
  const Tensor* y = node.out[0];
  if (!(st = expect_f32(node, y, "output", false))) return st;
  auto& s = node.state_as<ConcatState>();
  s.rows = int(y->rows());
  int total = 0;
  for (int i = 0; i < node.n_in; ++i) {
    const Tensor* x = node.in[i];
    if (!(st = expect_f32(node, x, "input", false))) return st;
    APRT_OP_ENSURE(node, x->rows() == y->rows(), Errc::kShapeMismatch,
                   "input %d has %zu rows, output %zu", i, x->rows(), y->rows());
    s.widths[i] = x->last_dim();
    total += x->last_dim();
  }
  APRT_OP_ENSURE(node, total == y->last_dim(), Errc::kShapeMismatch,
                 "inputs add up to %d columns, output has %d", total, y->last_dim());
  node.eval = eval_concat_ref;
  return ok();
}

}  // namespace aprt::ops
