// A labelled sequence's pose list ("name x y z qw qx qy qz" per line, '#'
// comments; DeepLoc's poses.txt, aprt_synth's lidar_poses.txt). Offline and
// start-up use: allocates.
#pragma once

#include <vector>

#include "runtime/base/expected.h"

namespace aprt {

struct ReplayEntry {
  char name[128] = {};
  double position[3] = {};
  double orientation[4] = {1, 0, 0, 0};  // w x y z, normalised
  double time_s = -1.0;                  // from times.txt, or -1
};

// Appends every entry of `path`; an unreadable file, a malformed line (named
// with its number), a zero quaternion or an empty list is an error.
Status read_pose_list(const char* path, std::vector<ReplayEntry>* out);

}  // namespace aprt
