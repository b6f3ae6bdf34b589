// An ensemble's members' outputs merged into one network's (FORMAT.md 1.5).
//
// An ensemble file's output is its n members' 13 outputs side by side, all
// under the file's position bounds (aprt_tools ensemble). They cannot be
// averaged by the graph: each network regresses a quaternion up to sign (q
// and -q are one rotation, and the loss does not care), and two networks
// trained apart pick different signs in different places, so a plain mean
// of their quaternions cancels. Merged here:
//   - position and the six log error scales: the members' mean;
//   - quaternion: the mean of the members' quaternions, each turned to the
//     sign of the reference (the member of largest norm), unnormalised as a
//     network's would be (decode_pose checks and normalises it);
//   - the members' disagreement (Lakshminarayanan et al. 2017): the
//     population standard deviation of their positions (normalised units,
//     per map axis), and the root mean square of their rotations from the
//     merged one (rad, per camera axis, as the confidence outputs' errors).
// Mirrored by tools/aprt_tools/ensemble_merge.py, which the calibration uses.
#pragma once

#include <cstdint>

namespace aprt {

inline constexpr int kMaxEnsembleMembers = 8;
inline constexpr int kNetworkOutputs = 13;  // position 3, quaternion 4, log scales 6

struct MergedOutputs {
  float raw[kNetworkOutputs] = {};
  double position_sd[3] = {};  // normalised units
  double rotation_sd[3] = {};  // rad
};

// raw: n (2..kMaxEnsembleMembers) members' 13 outputs. Non-finite inputs
// give non-finite outputs (decode_pose flags them). @rt: no allocation.
MergedOutputs merge_members(const float* raw, int n) noexcept;

}  // namespace aprt
