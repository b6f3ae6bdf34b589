#include "drivers/input/replay/pose_list.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "runtime/base/check.h"
#include "runtime/base/file_io.h"
#include "runtime/base/text_lines.h"

namespace aprt {

Status parse_pose_list(std::string_view text, const char* path, std::vector<ReplayEntry>* out) {
  const size_t before = out->size();
  Status s = each_text_line(text, "replay", path, true, [&](char* line, int lineno) -> Status {
    char* f[8];
    const int n = split_fields(line, f, 8);
    APRT_ENSURE(n == 8, Errc::kBadMetadata,
                "replay: %s:%d: expected 'name x y z qw qx qy qz', got %s fields", path, lineno,
                n > 8 ? "more than 8" : std::to_string(n).c_str());
    ReplayEntry e;
    APRT_ENSURE(std::strlen(f[0]) < sizeof e.name, Errc::kBadMetadata,
                "replay: %s:%d: a frame name of %zu bytes (at most %zu)", path, lineno,
                std::strlen(f[0]), sizeof e.name - 1);
    std::snprintf(e.name, sizeof e.name, "%s", f[0]);
    double v[7];
    for (int k = 0; k < 7; ++k) {
      APRT_ENSURE(parse_finite(f[1 + k], &v[k]), Errc::kBadMetadata,
                  "replay: %s:%d: '%s' is not a finite number", path, lineno, f[1 + k]);
    }
    // A map frame's coordinates (UTM northings reach 1e7 m); a quaternion
    // about unit length (its squares must not overflow: found by fuzzing).
    for (int k = 0; k < 3; ++k) {
      APRT_ENSURE(std::fabs(v[k]) <= kMaxPoseListCoordinate, Errc::kBadMetadata,
                  "replay: %s:%d: coordinate %g m is beyond +-%g m", path, lineno, v[k],
                  kMaxPoseListCoordinate);
    }
    for (int k = 3; k < 7; ++k) {
      APRT_ENSURE(std::fabs(v[k]) <= 1e3, Errc::kBadMetadata,
                  "replay: %s:%d: quaternion component %g (a unit quaternion's are in [-1, 1])",
                  path, lineno, v[k]);
    }
    const double qn = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
    APRT_ENSURE(qn > 1e-9, Errc::kBadMetadata, "replay: %s:%d: zero quaternion", path, lineno);
    for (int k = 0; k < 3; ++k) e.position[k] = v[k];
    for (int k = 0; k < 4; ++k) e.orientation[k] = v[3 + k] / qn;
    APRT_ENSURE(out->size() - before < kMaxPoseListEntries, Errc::kBadMetadata,
                "replay: %s: more than %zu frames", path, kMaxPoseListEntries);
    out->push_back(e);
    return ok();
  });
  if (!s) return s;
  APRT_ENSURE(out->size() > before, Errc::kBadMetadata, "replay: %s lists no frames", path);
  return ok();
}

Status read_pose_list(const char* path, std::vector<ReplayEntry>* out) {
  std::string text;
  if (Status s = read_input_file(path, kMaxPoseListBytes, "replay: pose list", &text); !s) {
    return s;
  }
  return parse_pose_list(text, path, out);
}

Status parse_times(std::string_view text, const char* path, std::vector<ReplayEntry>* entries) {
  size_t k = 0;
  double last = -INFINITY;
  Status s = each_text_line(text, "replay", path, true, [&](char* line, int lineno) -> Status {
    char* f[2];
    const int n = split_fields(line, f, 2);
    APRT_ENSURE(n == 2, Errc::kBadMetadata, "replay: %s:%d: expected 'name seconds'", path, lineno);
    APRT_ENSURE(k < entries->size(), Errc::kBadMetadata,
                "replay: %s:%d: more times than the %zu frames of the pose list", path, lineno,
                entries->size());
    APRT_ENSURE(std::strcmp(f[0], (*entries)[k].name) == 0, Errc::kBadMetadata,
                "replay: %s:%d: '%s' where the pose list has '%s'", path, lineno, f[0],
                (*entries)[k].name);
    double t = 0;
    APRT_ENSURE(parse_finite(f[1], &t), Errc::kBadMetadata,
                "replay: %s:%d: '%s' is not a finite number of seconds", path, lineno, f[1]);
    APRT_ENSURE(t > last, Errc::kBadMetadata,
                "replay: %s:%d: %g s is not after the previous frame's %g s", path, lineno, t,
                last);
    last = t;
    (*entries)[k++].time_s = t;
    return ok();
  });
  if (!s) return s;
  APRT_ENSURE(k == entries->size(), Errc::kBadMetadata,
              "replay: %s has times for %zu of the %zu frames", path, k, entries->size());
  return ok();
}

}  // namespace aprt
