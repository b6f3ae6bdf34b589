// SQUEEZE_EXCITE: y = x * sigmoid(W2 silu(W1 mean_hw(x) + b1) + b2), per channel.
// inputs: X [1,H,W,C], W1 [Cr,C], B1 [Cr], W2 [C,Cr], B2 [C]
#include "kernels/ref/f32_squeeze_excite__ref.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

struct SeState {
  int pixels, c, cr;
};

void eval_se_ref(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<SeState>();
  kernels::f32_squeeze_excite__ref(s.pixels, s.c, s.cr, node.in[0]->f32(), node.in[1]->f32(),
                                   node.in[2]->f32(), node.in[3]->f32(), node.in[4]->f32(),
                                   node.out[0]->f32(), ctx.scratch);
}

}  // namespace

Status prepare_squeeze_excite(OpNode& node) {
  const Tensor* x = node.in[0];
  const Tensor* y = node.out[0];
  Status st;
  if (!(st = expect_f32(node, x, "input", false))) return st;
  if (!(st = expect_f32(node, y, "output", false))) return st;
  const int xd[4] = {1, -1, -1, -1};
  if (!(st = expect_dims(node, x, "input", 4, xd))) return st;
  const int c = x->dims[3];
  APRT_OP_ENSURE(node, node.n_in == 5, Errc::kBadOp, "needs 5 inputs, has %d", node.n_in);
  for (int i = 1; i < 5; ++i) {
    if (!(st = expect_f32(node, node.in[i], "weights", true))) return st;
  }
  const int cr = node.in[1]->rank == 2 ? node.in[1]->dims[0] : -1;
  APRT_OP_ENSURE(node, cr >= 1, Errc::kShapeMismatch, "reduce weights must be [Cr, C]");
  const int w1[2] = {cr, c}, b1[1] = {cr}, w2[2] = {c, cr}, b2[1] = {c};
  if (!(st = expect_dims(node, node.in[1], "reduce weights", 2, w1))) return st;
  if (!(st = expect_dims(node, node.in[2], "reduce bias", 1, b1))) return st;
  if (!(st = expect_dims(node, node.in[3], "expand weights", 2, w2))) return st;
  if (!(st = expect_dims(node, node.in[4], "expand bias", 1, b2))) return st;
  APRT_OP_ENSURE(node, y->numel == x->numel, Errc::kShapeMismatch,
                 "output has %zu elements, input %zu", y->numel, x->numel);
  auto& s = node.state_as<SeState>();
  s = {x->dims[1] * x->dims[2], c, cr};
  node.scratch_floats = kernels::f32_squeeze_excite__ref_scratch(c, cr);
  node.flops = 2ull * (uint64_t(s.pixels) * c + 2ull * c * cr);
  node.eval = eval_se_ref;
  return ok();
}

}  // namespace aprt::ops
