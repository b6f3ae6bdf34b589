// DWCONV2D with int8 weights (issue #4); shapes and padding are validated by
// the DWCONV2D prepare in conv2d_op.cc, which hands over here.
//   inputs: X f32 [1,H,W,C], W i8 [KH,KW,C] (symmetric, per-channel scales [C]
//           or one per-tensor scale), B f32 [C]
//   params: stride_h, stride_w, pad_t, pad_l, pad_b, pad_r, act, input scale
//           (f32 bits, > 0), input zero point (0..255)
// eval: X quantised to uint8 into scratch; the kernel accumulates exactly and
// applies y = act(mult[c] * acc + bias[c]), mult[c] = input scale x weight scale[c].
#include "kernels/dwconv/qu8s8_dwconv2d__ref.h"
#include "kernels/gemm/qs8_gemm.h"
#include "kernels/gemm/qu8s8_gemm__ref.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

struct QDwState {
  kernels::Conv2dShape shape;
  kernels::Act act;
  float a_scale, a_inv_scale;
  int32_t a_zero;
  Split rows;
  size_t w_at;  // floats into node.packed: mult [C] at 0, then the weights as floats
};

size_t input_bytes(const QDwState& s) {
  return size_t(s.shape.in_h) * s.shape.in_w * s.shape.in_c;
}

void eval_qdwconv_ref(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<QDwState>();
  auto* q = reinterpret_cast<uint8_t*>(ctx.scratch);
  kernels::f32_qu8_quantize__ref(input_bytes(s), node.in[0]->f32(), s.a_inv_scale, s.a_zero, q);
  kernels::qu8s8_dwconv2d__ref(s.shape, q, s.a_zero, static_cast<const int8_t*>(node.in[1]->data),
                               node.packed, node.in[2]->f32(), s.act, node.out[0]->f32());
}

struct QDwTask {
  const OpNode* node;
  kernels::QDwConvArgs args;
};

void qdwconv_task(void* data, int task, int) {
  const auto* t = static_cast<const QDwTask*>(data);
  const auto& s = t->node->state_as<QDwState>();
  t->node->qks->dwconv_rows(t->args, s.rows.begin(task), s.rows.end(task));
}

void eval_qdwconv_fast(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<QDwState>();
  auto* q = reinterpret_cast<uint8_t*>(ctx.scratch);
  node.qks->quantize(input_bytes(s), node.in[0]->f32(), s.a_inv_scale, s.a_zero, q);
  QDwTask t{&node,
            {s.shape, q, s.a_zero, node.packed + s.w_at, node.packed, node.in[2]->f32(), s.act,
             node.out[0]->f32()}};
  parallel_for(ctx, s.rows.tasks, qdwconv_task, &t);
}

void pack_qdwconv(OpNode& node) {
  const auto& s = node.state_as<QDwState>();
  const Tensor* w = node.in[1];
  const int C = s.shape.in_c;
  for (int c = 0; c < C; ++c)
    node.packed[c] = s.a_scale * (w->qscale ? w->qscale->f32()[c] : w->scale);
  if (!node.qks) return;
  const auto* wq = static_cast<const int8_t*>(w->data);
  for (size_t i = 0; i < w->numel; ++i) node.packed[s.w_at + i] = float(wq[i]);
}

}  // namespace

// By value: the caller's copies live in node.state, which this overwrites.
Status prepare_qdwconv2d(OpNode& node, kernels::Conv2dShape shape, Split rows) {
  const Tensor* w = node.in[1];
  const int C = shape.in_c;
  Status st;
  if (!(st = expect_int8_weights(node, w, C))) return st;
  APRT_OP_ENSURE(node, shape.kernel_h * shape.kernel_w <= kernels::kMaxQDwTaps, Errc::kUnsupported,
                 "int8 depthwise kernel %dx%d has more than %d taps", shape.kernel_h,
                 shape.kernel_w, kernels::kMaxQDwTaps);
  float a_scale;
  int32_t a_zero;
  if (!(st = expect_input_quantisation(node, 7, &a_scale, &a_zero))) return st;
  auto& s = node.state_as<QDwState>();
  s.shape = shape;
  s.act = static_cast<kernels::Act>(node.params[6]);
  s.a_scale = a_scale;
  s.a_inv_scale = 1.0f / a_scale;
  s.a_zero = a_zero;
  s.rows = rows;
  s.w_at = floats_for_bytes(size_t(C) * 4);
  node.scratch_floats = floats_for_bytes(input_bytes(s));
  node.pack = pack_qdwconv;
  if (node.qks) {
    node.packed_floats = s.w_at + floats_for_bytes(w->numel * 4);
    node.packed_inputs = 1u << 1;
    node.packed_layout = "f32 scales + depthwise filters as f32";
    node.eval = eval_qdwconv_fast;
    node.kernel = node.qks->isa;
  } else {
    node.packed_floats = s.w_at;
    node.packed_layout = "f32 output scales";
    node.eval = eval_qdwconv_ref;
    node.kernel = "ref-int8";
  }
  return ok();
}

}  // namespace aprt::ops
