// A labelled sequence's pose list ("name x y z qw qx qy qz" per line, '#'
// comments; DeepLoc's poses.txt, aprt_synth's lidar_poses.txt) and its
// optional recorded times (times.txt: "name seconds" per line). Offline and
// start-up use: allocates. The parsers take text (fuzzed:
// tests/fuzz/replay_lists_fuzz.cc); the readers add the bounded file I/O.
#pragma once

#include <cstddef>
#include <string_view>
#include <vector>

#include "runtime/base/expected.h"

namespace aprt {

struct ReplayEntry {
  char name[128] = {};
  double position[3] = {};
  double orientation[4] = {1, 0, 0, 0};  // w x y z, normalised
  double time_s = -1.0;                  // from times.txt, or -1
};

// The most a list may hold: a file larger is refused before it is read.
inline constexpr size_t kMaxPoseListBytes = size_t(64) << 20;
inline constexpr size_t kMaxPoseListEntries = 1000000;
inline constexpr double kMaxPoseListCoordinate = 1e7;  // metres

// Appends every entry of `text` (`path` names it in messages): a malformed
// line (named with its number: wrong field count, a number that does not
// parse whole, a non-finite value, trailing text, a name of 128 bytes or
// more, a line of 1024 bytes or more), a coordinate beyond
// kMaxPoseListCoordinate, a quaternion component beyond 1000 or a zero
// quaternion, more than
// kMaxPoseListEntries or an empty list is an error.
Status parse_pose_list(std::string_view text, const char* path, std::vector<ReplayEntry>* out);
// The same from a file (a regular file of at most kMaxPoseListBytes).
Status read_pose_list(const char* path, std::vector<ReplayEntry>* out);

// times.txt for `entries` (in their order): every entry's name and a finite
// time, strictly increasing; anything else is an error naming the line.
Status parse_times(std::string_view text, const char* path, std::vector<ReplayEntry>* entries);

}  // namespace aprt
