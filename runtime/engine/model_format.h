// The numbers of the model_bin format. model_bin/FORMAT.md is the normative
// text; tools/aprt_tools/model_bin/spec.py carries the same numbers for the
// writer, and tests/tools/test_spec_agreement.py checks that they agree.
#pragma once

#include <cstddef>
#include <cstdint>

namespace aprt::format {

inline constexpr char kMagic[8] = {'A', 'P', 'R', 'T', 'M', 'D', 'L', '\0'};
inline constexpr uint16_t kVersionMajor = 1;
// 1.1: int8 weights; 1.2: point ops; 1.3: confidence; 1.4: ensembles; 1.5: an
// ensemble's member positions in its output (FORMAT.md)
inline constexpr uint16_t kVersionMinor = 5;
inline constexpr uint32_t kHeaderBytes = 64;
inline constexpr uint32_t kSectionEntryBytes = 32;
inline constexpr uint32_t kTensorEntryBytes = 64;
inline constexpr uint32_t kOpEntryBytes = 96;
inline constexpr uint32_t kTablePrefixBytes = 16;  // count, entry size, 2 reserved
inline constexpr uint32_t kAlign = 64;
inline constexpr uint32_t kEndianMark = 0x01020304u;
inline constexpr uint32_t kMaxSections = 16;
inline constexpr int kMaxOpInputs = 8;
inline constexpr int kMaxOpOutputs = 2;
inline constexpr int kMaxOpParams = 12;
inline constexpr int kMaxRank = 4;

// Limits that turn absurd files into errors before any size arithmetic can overflow.
inline constexpr uint32_t kMaxDim = 1u << 20;
inline constexpr uint64_t kMaxTensorElements = 1ull << 28;
inline constexpr uint32_t kMaxTensors = 1u << 16;
// Pose bounds (META pose_min/pose_max): a map frame's coordinates and extent, metres.
inline constexpr float kMaxPoseCoordinate = 1e7f;
inline constexpr float kMaxPoseExtent = 1e6f;
inline constexpr uint32_t kMaxOps = 1u << 15;

constexpr uint32_t fourcc(char a, char b, char c, char d) {
  return uint32_t(uint8_t(a)) | uint32_t(uint8_t(b)) << 8 | uint32_t(uint8_t(c)) << 16 |
         uint32_t(uint8_t(d)) << 24;
}
inline constexpr uint32_t kSecMeta = fourcc('M', 'E', 'T', 'A');
inline constexpr uint32_t kSecStrings = fourcc('S', 'T', 'R', 'S');
inline constexpr uint32_t kSecTensors = fourcc('T', 'E', 'N', 'S');
inline constexpr uint32_t kSecOps = fourcc('O', 'P', 'S', 'Q');
inline constexpr uint32_t kSecWeights = fourcc('W', 'G', 'H', 'T');

enum class DType : uint8_t { kF32 = 1, kI8 = 2, kI32 = 3, kU8 = 4 };
enum class TensorKind : uint8_t { kConst = 1, kActivation = 2, kInput = 3, kOutput = 4 };

enum class OpCode : uint16_t {
  kConv2d = 1,
  kDwConv2d = 2,
  kLinear = 3,
  kSqueezeExcite = 4,
  kAdd = 5,
  kLayerNorm = 6,
  kAttention = 7,
  kActivation = 8,
  kConcat = 9,
  kCrossAttention1q = 10,
  // 1.2: the raw-points modality (PointNet++)
  kFps = 11,
  kBallGroup = 12,
  kGroupMax = 13,
  kThreeInterp = 14,
  kGridTokens = 15,
};
inline constexpr uint16_t kMaxOpCode = 15;

enum class Act : int32_t { kNone = 0, kSilu = 1, kGelu = 2, kSigmoid = 3, kRelu = 4 };
inline constexpr int32_t kMaxAct = 4;

// META record types and keys.
enum class MetaType : uint16_t { kU32 = 1, kF32 = 2, kStr = 3, kBytes = 4 };
enum class MetaKey : uint16_t {
  kProducer = 1,
  kSourceSha256 = 2,
  kSourceName = 3,
  kModality = 10,
  kInputShape = 11,
  kNormMean = 12,
  kNormStd = 13,
  kResizePolicy = 14,
  kPoseMin = 20,
  kPoseMax = 21,
  kBackbone = 30,
  kDModel = 31,
  kNHeads = 32,
  kEncLayers = 33,
  kDecLayers = 34,
  kDimFeedforward = 35,
  kValError = 40,
  kConfigJson = 41,
  kQuantization = 42,
  kUncertainty = 43,
  kEnsemble = 44,
  kBev = 50,
  kPoints = 51,
};

enum class Modality : uint32_t { kImage = 1, kLidarBev = 2, kLidarPoints = 3 };
enum class ResizePolicy : uint32_t { kShorterThenCenterCrop = 1, kStretch = 2 };

size_t dtype_bytes(DType t) noexcept;
const char* dtype_name(DType t) noexcept;
const char* op_name(OpCode code) noexcept;
const char* modality_name(Modality m) noexcept;
const char* act_name(Act a) noexcept;

}  // namespace aprt::format
