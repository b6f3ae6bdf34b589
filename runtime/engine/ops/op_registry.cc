// The op kinds this build runs, indexed by opcode.
#include "runtime/engine/op_node.h"
#include "runtime/engine/ops/ops.h"

namespace aprt {
namespace {

constexpr OpKind kKinds[] = {
    {"CONV2D", 3, 4, ops::prepare_conv2d},
    {"DWCONV2D", 3, 3, ops::prepare_dwconv2d},
    {"LINEAR", 3, 4, ops::prepare_linear},
    {"SQUEEZE_EXCITE", 5, 5, ops::prepare_squeeze_excite},
    {"ADD", 2, 2, ops::prepare_add},
    {"LAYERNORM", 3, 3, ops::prepare_layernorm},
    {"ATTENTION", 3, 3, ops::prepare_attention},
    {"ACTIVATION", 1, 1, ops::prepare_activation},
    {"CONCAT", 1, format::kMaxOpInputs, ops::prepare_concat},
    {"CROSS_ATTENTION_1Q", 7, 7, ops::prepare_cross_attention_1q},
    {"FPS", 1, 1, ops::prepare_fps},
    {"BALL_GROUP", 2, 3, ops::prepare_ball_group},
    {"GROUP_MAX", 1, 1, ops::prepare_group_max},
    {"THREE_INTERP", 3, 3, ops::prepare_three_interp},
    {"GRID_TOKENS", 2, 2, ops::prepare_grid_tokens},
};
static_assert(sizeof(kKinds) / sizeof(kKinds[0]) == format::kMaxOpCode);

}  // namespace

const OpKind* find_op_kind(format::OpCode code) {
  const int i = static_cast<int>(code) - 1;
  if (i < 0 || i >= format::kMaxOpCode) return nullptr;
  return &kKinds[i];
}

}  // namespace aprt
