// SQUEEZE_EXCITE: y = x * sigmoid(W2 silu(W1 mean_hw(x) + b1) + b2), per channel.
// inputs: X [1,H,W,C], W1 [Cr,C], B1 [Cr], W2 [C,Cr], B2 [C]
// Fast path: the gate is computed once (one thread: its mean is a reduction
// whose order must not depend on the thread count), then pixels are scaled in
// parallel. W2 is transposed at load so the gate is computed with vectors.
#include "kernels/rowwise/f32_squeeze_excite__ref.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

struct SeState {
  int pixels, c, cr;
  Split pixel_split;
};

void eval_se_ref(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<SeState>();
  kernels::f32_squeeze_excite__ref(s.pixels, s.c, s.cr, node.in[0]->f32(), node.in[1]->f32(),
                                   node.in[2]->f32(), node.in[3]->f32(), node.in[4]->f32(),
                                   node.out[0]->f32(), ctx.scratch);
}

struct SeTask {
  const OpNode* node;
  const float* gate;
};

void se_scale_task(void* data, int task, int) {
  const auto* t = static_cast<const SeTask*>(data);
  const auto& s = t->node->state_as<SeState>();
  t->node->ks->se_scale(s.c, t->node->in[0]->f32(), t->gate, t->node->out[0]->f32(),
                        s.pixel_split.begin(task), s.pixel_split.end(task));
}

void eval_se_fast(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<SeState>();
  float* gate = ctx.scratch;
  node.ks->se_gate(s.pixels, s.c, s.cr, node.in[0]->f32(), node.in[1]->f32(), node.in[2]->f32(),
                   node.packed, node.in[4]->f32(), gate, ctx.scratch + s.c);
  SeTask t{&node, gate};
  parallel_for(ctx, s.pixel_split.tasks, se_scale_task, &t);
}

void pack_se(OpNode& node) {
  const auto& s = node.state_as<SeState>();
  const float* w2 = node.in[3]->f32();
  for (int c = 0; c < s.c; ++c) {
    for (int r = 0; r < s.cr; ++r) node.packed[size_t(r) * s.c + c] = w2[size_t(c) * s.cr + r];
  }
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
  s.pixels = x->dims[1] * x->dims[2];
  s.c = c;
  s.cr = cr;
  node.flops = 2ull * (uint64_t(s.pixels) * c + 2ull * c * cr);
  if (node.ks) {
    const int min_pixels = 32768 / (c > 0 ? c : 1) + 1;
    int tasks = node.threads <= 1 ? 1 : 4 * node.threads;
    if (tasks > s.pixels / min_pixels) tasks = s.pixels / min_pixels;
    s.pixel_split = make_split(s.pixels, 1, tasks < 1 ? 1 : tasks);
    node.scratch_floats = size_t(2 * c + cr);
    node.packed_floats = size_t(c) * cr;
    node.pack = pack_se;
    node.packed_inputs = 1u << 3;
    node.packed_layout = "f32 expand weights transposed [cr][c]";
    node.eval = eval_se_fast;
    node.kernel = node.ks->isa;
  } else {
    node.scratch_floats = kernels::f32_squeeze_excite__ref_scratch(c, cr);
    node.eval = eval_se_ref;
  }
  return ok();
}

}  // namespace aprt::ops
