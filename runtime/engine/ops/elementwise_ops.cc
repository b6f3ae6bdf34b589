// ADD (a + b, same element count), ACTIVATION (params: act) and CONCAT (row-wise).
#include "kernels/rowwise/f32_elementwise__ref.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

struct EltState {
  kernels::Act act;
  Split split;  // elements
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
  kernels::f32_activation__ref(node.out[0]->numel, node.state_as<EltState>().act, node.in[0]->f32(),
                               node.out[0]->f32());
}

void add_task(void* data, int task, int) {
  const auto& node = *static_cast<const OpNode*>(data);
  const auto& s = node.state_as<EltState>();
  node.ks->add(node.in[0]->f32(), node.in[1]->f32(), node.out[0]->f32(),
               size_t(s.split.begin(task)), size_t(s.split.end(task)));
}

void activation_task(void* data, int task, int) {
  const auto& node = *static_cast<const OpNode*>(data);
  const auto& s = node.state_as<EltState>();
  node.ks->activation(s.act, node.in[0]->f32(), node.out[0]->f32(), size_t(s.split.begin(task)),
                      size_t(s.split.end(task)));
}

void eval_add_fast(const OpNode& node, const RunContext& ctx) {
  parallel_for(ctx, node.state_as<EltState>().split.tasks, add_task, const_cast<OpNode*>(&node));
}

void eval_activation_fast(const OpNode& node, const RunContext& ctx) {
  parallel_for(ctx, node.state_as<EltState>().split.tasks, activation_task,
               const_cast<OpNode*>(&node));
}

void eval_concat_ref(const OpNode& node, const RunContext&) {
  const auto& s = node.state_as<ConcatState>();
  const float* xs[format::kMaxOpInputs];
  for (int i = 0; i < node.n_in; ++i) xs[i] = node.in[i]->f32();
  kernels::f32_concat_rows__ref(s.rows, node.n_in, xs, s.widths, node.out[0]->f32());
}

Split element_split(const OpNode& node, size_t n, size_t min_per_task) {
  int tasks = node.threads <= 1 ? 1 : 2 * node.threads;
  if (size_t(tasks) > n / min_per_task) tasks = int(n / min_per_task);
  return make_split(int(n), 64, tasks < 1 ? 1 : tasks);
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
  if (node.ks) {
    node.state_as<EltState>().split = element_split(node, node.out[0]->numel, 32768);
    node.eval = eval_add_fast;
    node.kernel = node.ks->isa;
  } else {
    node.eval = eval_add_ref;
  }
  return ok();
}

Status prepare_activation(OpNode& node) {
  Status st;
  if (!(st = expect_f32(node, node.in[0], "input", false))) return st;
  if (!(st = expect_f32(node, node.out[0], "output", false))) return st;
  if (!(st = expect_act(node, node.params[0]))) return st;
  APRT_OP_ENSURE(node, node.in[0]->numel == node.out[0]->numel, Errc::kShapeMismatch,
                 "input has %zu elements, output %zu", node.in[0]->numel, node.out[0]->numel);
  auto& s = node.state_as<EltState>();
  s.act = static_cast<kernels::Act>(node.params[0]);
  node.flops = node.out[0]->numel;
  if (node.ks) {
    s.split = element_split(node, node.out[0]->numel, 8192);
    node.eval = eval_activation_fast;
    node.kernel = node.ks->isa;
  } else {
    node.eval = eval_activation_ref;
  }
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
