// The flags a pose can carry beyond the network output's own
// (runtime/engine/pose_decode.h, bits 0..7): what the loop, the fusion and the
// validity gate found. A pose with any flag is not published as valid.
#pragma once

#include <cstdint>
#include <cstdio>

namespace aprt {

// Flags the loop adds to the pose's own (runtime/engine/pose_decode.h, bits 0..3).
inline constexpr uint32_t kPoseStaleFrame = 1u << 8;      // frame older than frame_timeout
inline constexpr uint32_t kPoseDeadlineMissed = 1u << 9;  // inference over its deadline
inline constexpr uint32_t kPoseJump = 1u << 10;           // implausible jump from the last pose
inline constexpr uint32_t kPoseNoQuorum = 1u << 11;       // cameras disagree: no majority (fusion)
inline constexpr uint32_t kPoseSparseScan = 1u << 12;     // LiDAR: too few points (padded or empty)
inline constexpr uint32_t kPoseNoOdometry = 1u << 13;     // the pose filter has no vehicle motion
// The validity gate's (runtime/pose/pose_gate.h): the pose is withheld, the
// system is fine.
// Bits 5..7 (free in the network output's range; CAN's 16-bit Flags keeps
// bit 15 for a saturated signal).
inline constexpr uint32_t kPoseUncertain = 1u << 5;     // the model's own sigma is too large
inline constexpr uint32_t kPoseInconsistent = 1u << 6;  // disagrees with the vehicle's motion
inline constexpr uint32_t kPoseUnconfirmed = 1u << 7;   // no confirmed track yet

// Each bit's name (docs/outputs.md, "Validity"), bit order; nullptr: unused.
inline constexpr const char* kPoseFlagNames[16] = {
    "non-finite",   "quat-degenerate", "quat-norm", "out-of-bounds", "no-confidence", "uncertain",
    "inconsistent", "unconfirmed",     "stale",     "late",          "jump",          "no-quorum",
    "sparse",       "no-odometry",     nullptr,     nullptr};

// "ok" or the names of the flags set, comma-separated, into `buf`.
inline const char* pose_flag_names(uint32_t flags, char* buf, int size) noexcept {
  if (size <= 0) return buf;
  int used = std::snprintf(buf, size_t(size), "%s", flags ? "" : "ok");
  for (int bit = 0; bit < 16; ++bit) {
    if (!(flags & (1u << bit)) || !kPoseFlagNames[bit]) continue;
    used += std::snprintf(buf + used, used < size ? size_t(size - used) : 0, "%s%s",
                          used ? "," : "", kPoseFlagNames[bit]);
  }
  return buf;
}

}  // namespace aprt
