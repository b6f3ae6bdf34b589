// The names of the model format's enumerations, for messages and `aprt info`.
#include "runtime/engine/model_format.h"

namespace aprt::format {

size_t dtype_bytes(DType t) noexcept {
  switch (t) {
    case DType::kF32: return 4;
    case DType::kI8: return 1;
    case DType::kI32: return 4;
    case DType::kU8: return 1;
  }
  return 0;
}

const char* dtype_name(DType t) noexcept {
  switch (t) {
    case DType::kF32: return "f32";
    case DType::kI8: return "i8";
    case DType::kI32: return "i32";
    case DType::kU8: return "u8";
  }
  return "?";
}

const char* op_name(OpCode code) noexcept {
  switch (code) {
    case OpCode::kConv2d: return "CONV2D";
    case OpCode::kDwConv2d: return "DWCONV2D";
    case OpCode::kLinear: return "LINEAR";
    case OpCode::kSqueezeExcite: return "SQUEEZE_EXCITE";
    case OpCode::kAdd: return "ADD";
    case OpCode::kLayerNorm: return "LAYERNORM";
    case OpCode::kAttention: return "ATTENTION";
    case OpCode::kActivation: return "ACTIVATION";
    case OpCode::kConcat: return "CONCAT";
    case OpCode::kCrossAttention1q: return "CROSS_ATTENTION_1Q";
    case OpCode::kFps: return "FPS";
    case OpCode::kBallGroup: return "BALL_GROUP";
    case OpCode::kGroupMax: return "GROUP_MAX";
    case OpCode::kThreeInterp: return "THREE_INTERP";
    case OpCode::kGridTokens: return "GRID_TOKENS";
  }
  return "?";
}

const char* modality_name(Modality m) noexcept {
  switch (m) {
    case Modality::kImage: return "image";
    case Modality::kLidarBev: return "lidar_bev";
    case Modality::kLidarPoints: return "lidar_points";
  }
  return "?";
}

const char* act_name(Act a) noexcept {
  switch (a) {
    case Act::kNone: return "none";
    case Act::kSilu: return "silu";
    case Act::kGelu: return "gelu";
    case Act::kSigmoid: return "sigmoid";
    case Act::kRelu: return "relu";
  }
  return "?";
}

}  // namespace aprt::format
