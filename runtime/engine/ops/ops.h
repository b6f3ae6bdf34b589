// prepare() of every op kind (each file in this folder implements one or a few).
#pragma once

#include "runtime/engine/op_node.h"

namespace aprt::ops {

Status prepare_conv2d(OpNode& node);
Status prepare_dwconv2d(OpNode& node);
// DWCONV2D with int8 weights, after the shared shape checks of prepare_dwconv2d
// (by value: the caller's ConvState shares node.state with this op's state).
Status prepare_qdwconv2d(OpNode& node, kernels::Conv2dShape shape, Split rows);
Status prepare_linear(OpNode& node);
Status prepare_qlinear(OpNode& node);  // LINEAR with int8 weights
Status prepare_squeeze_excite(OpNode& node);
Status prepare_add(OpNode& node);
Status prepare_layernorm(OpNode& node);
Status prepare_attention(OpNode& node);
Status prepare_activation(OpNode& node);
Status prepare_concat(OpNode& node);
Status prepare_cross_attention_1q(OpNode& node);
// The raw-points modality (point_ops.cc).
Status prepare_fps(OpNode& node);
Status prepare_ball_group(OpNode& node);
Status prepare_group_max(OpNode& node);
Status prepare_three_interp(OpNode& node);
Status prepare_grid_tokens(OpNode& node);

}  // namespace aprt::ops
