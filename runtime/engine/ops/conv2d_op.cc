// CONV2D and DWCONV2D: NHWC convolutions with explicit asymmetric zero padding.
// inputs: X [1,H,W,Ci], W (dense [Co,KH,KW,Ci] | depthwise [KH,KW,C]), B [Co], R? (dense only)
// params: stride_h, stride_w, pad_top, pad_left, pad_bottom, pad_right, act
// Fast path: output rows split across threads; dense weights repacked at load
// to [KH][KW][Ci][Co] so output channels are the vector dimension.
#include "kernels/conv/f32_conv2d__ref.h"
#include "kernels/dwconv/f32_dwconv2d__ref.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

struct ConvState {
  kernels::Conv2dShape shape;
  kernels::Act act;
  Split rows;
};

const float* residual_of(const OpNode& node) {
  return node.n_in > 3 && node.in[3] ? node.in[3]->f32() : nullptr;
}

void eval_conv2d_ref(const OpNode& node, const RunContext&) {
  const auto& s = node.state_as<ConvState>();
  kernels::f32_conv2d__ref(s.shape, node.in[0]->f32(), node.in[1]->f32(), node.in[2]->f32(),
                           residual_of(node), s.act, node.out[0]->f32());
}

void eval_dwconv2d_ref(const OpNode& node, const RunContext&) {
  const auto& s = node.state_as<ConvState>();
  kernels::f32_dwconv2d__ref(s.shape, node.in[0]->f32(), node.in[1]->f32(), node.in[2]->f32(),
                             s.act, node.out[0]->f32());
}

void conv_task(void* data, int task, int) {
  const auto& node = *static_cast<const OpNode*>(data);
  const auto& s = node.state_as<ConvState>();
  node.ks->conv_rows(s.shape, node.in[0]->f32(), node.packed, node.in[2]->f32(), residual_of(node),
                     s.act, node.out[0]->f32(), s.rows.begin(task), s.rows.end(task));
}

void dwconv_task(void* data, int task, int) {
  const auto& node = *static_cast<const OpNode*>(data);
  const auto& s = node.state_as<ConvState>();
  node.ks->dwconv_rows(s.shape, node.in[0]->f32(), node.in[1]->f32(), node.in[2]->f32(), s.act,
                       node.out[0]->f32(), s.rows.begin(task), s.rows.end(task));
}

void eval_conv2d_fast(const OpNode& node, const RunContext& ctx) {
  parallel_for(ctx, node.state_as<ConvState>().rows.tasks, conv_task, const_cast<OpNode*>(&node));
}

void eval_dwconv2d_fast(const OpNode& node, const RunContext& ctx) {
  parallel_for(ctx, node.state_as<ConvState>().rows.tasks, dwconv_task, const_cast<OpNode*>(&node));
}

void pack_conv2d(OpNode& node) {
  const auto& s = node.state_as<ConvState>().shape;
  kernels::f32_conv2d_pack_weights(s.out_c, s.kernel_h, s.kernel_w, s.in_c, node.in[1]->f32(),
                                   node.packed);
}

Status prepare(OpNode& node, bool depthwise) {
  const Tensor* x = node.in[0];
  const Tensor* w = node.in[1];
  const Tensor* b = node.in[2];
  const Tensor* y = node.out[0];
  Status st;
  if (!(st = expect_f32(node, x, "input", false))) return st;
  const bool int8 = depthwise && w && w->dtype == format::DType::kI8;  // qdwconv2d_op.cc
  if (!int8 && !(st = expect_f32(node, w, "weights", true))) return st;
  if (!(st = expect_f32(node, b, "bias", true))) return st;
  if (!(st = expect_f32(node, y, "output", false))) return st;
  const int any4[4] = {1, -1, -1, -1};
  if (!(st = expect_dims(node, x, "input", 4, any4))) return st;
  if (!(st = expect_dims(node, y, "output", 4, any4))) return st;
  const int32_t* p = node.params;
  const int sh = p[0], sw = p[1], pt = p[2], pl = p[3], pb = p[4], pr = p[5];
  if (!(st = expect_act(node, p[6]))) return st;
  APRT_OP_ENSURE(node, sh >= 1 && sh <= 16 && sw >= 1 && sw <= 16, Errc::kBadOp,
                 "stride %dx%d out of range 1..16", sh, sw);
  const int ci = x->dims[3], co = y->dims[3];
  int kh, kw;
  if (depthwise) {
    const int wd[3] = {-1, -1, ci};
    if (!(st = expect_dims(node, w, "weights", 3, wd))) return st;
    kh = w->dims[0];
    kw = w->dims[1];
    APRT_OP_ENSURE(node, co == ci, Errc::kShapeMismatch,
                   "depthwise output has %d channels, input %d", co, ci);
    APRT_OP_ENSURE(node, node.n_in == 3, Errc::kBadOp, "depthwise convolution takes no residual");
  } else {
    const int wd[4] = {co, -1, -1, ci};
    if (!(st = expect_dims(node, w, "weights", 4, wd))) return st;
    kh = w->dims[1];
    kw = w->dims[2];
  }
  const int bd[1] = {co};
  if (!(st = expect_dims(node, b, "bias", 1, bd))) return st;
  APRT_OP_ENSURE(
      node, pt >= 0 && pl >= 0 && pb >= 0 && pr >= 0 && pt < kh && pb < kh && pl < kw && pr < kw,
      Errc::kBadOp, "padding (t%d l%d b%d r%d) invalid for a %dx%d kernel", pt, pl, pb, pr, kh, kw);
  const int ph = x->dims[1] + pt + pb, pw = x->dims[2] + pl + pr;
  APRT_OP_ENSURE(node, ph >= kh && pw >= kw, Errc::kShapeMismatch,
                 "padded input %dx%d is smaller than the %dx%d kernel", ph, pw, kh, kw);
  const int oh = (ph - kh) / sh + 1, ow = (pw - kw) / sw + 1;
  APRT_OP_ENSURE(node, y->dims[1] == oh && y->dims[2] == ow, Errc::kShapeMismatch,
                 "output is %dx%d, the convolution gives %dx%d", y->dims[1], y->dims[2], oh, ow);
  if (node.n_in > 3 && node.in[3]) {
    if (!(st = expect_f32(node, node.in[3], "residual", false))) return st;
    APRT_OP_ENSURE(node, node.in[3]->numel == y->numel, Errc::kShapeMismatch,
                   "residual has %zu elements, output %zu", node.in[3]->numel, y->numel);
  }
  auto& s = node.state_as<ConvState>();
  s.shape = {x->dims[1], x->dims[2], ci, oh, ow, co, kh, kw, sh, sw, pt, pl};
  s.act = static_cast<kernels::Act>(p[6]);
  node.flops = 2ull * uint64_t(oh) * ow * co * kh * kw * (depthwise ? 1 : ci);
  // Rows per task: at least ~32k multiply-adds each.
  const long long per_row = static_cast<long long>(node.flops / 2) / oh;
  const int min_rows = per_row > 0 ? int((32768 + per_row - 1) / per_row) : 1;
  int tasks = node.threads <= 1 ? 1 : 4 * node.threads;
  if (tasks > oh / (min_rows > 0 ? min_rows : 1)) tasks = oh / (min_rows > 0 ? min_rows : 1);
  s.rows = make_split(oh, 1, tasks < 1 ? 1 : tasks);
  if (int8) return prepare_qdwconv2d(node, s.shape, s.rows);
  if (node.ks) {
    node.kernel = node.ks->isa;
    if (depthwise) {
      node.eval = eval_dwconv2d_fast;
    } else {
      node.packed_floats = size_t(co) * kh * kw * ci;
      node.pack = pack_conv2d;
      node.packed_inputs = 1u << 1;
      node.packed_layout = "f32 conv filters [kh][kw][ci][co]";
      node.eval = eval_conv2d_fast;
    }
  } else {
    node.eval = depthwise ? eval_dwconv2d_ref : eval_conv2d_ref;
  }
  return ok();
}

}  // namespace

Status prepare_conv2d(OpNode& node) {
  return prepare(node, false);
}
Status prepare_dwconv2d(OpNode& node) {
  return prepare(node, true);
}

}  // namespace aprt::ops
