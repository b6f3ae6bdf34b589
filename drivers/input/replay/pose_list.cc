#include "drivers/input/replay/pose_list.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "runtime/base/check.h"

namespace aprt {

Status read_pose_list(const char* path, std::vector<ReplayEntry>* out) {
  FILE* f = std::fopen(path, "r");
  APRT_ENSURE(f != nullptr, Errc::kIo, "replay: cannot open %s: %s", path, std::strerror(errno));
  char line[512];
  int lineno = 0;
  const size_t before = out->size();
  while (std::fgets(line, sizeof line, f)) {
    ++lineno;
    char* s = line;
    while (*s == ' ' || *s == '\t') ++s;
    if (*s == '#' || *s == '\n' || *s == '\r' || *s == '\0') continue;
    ReplayEntry e;
    double v[7];
    int used = 0;
    const int n = std::sscanf(s, "%127s %lf %lf %lf %lf %lf %lf %lf %n", e.name, &v[0], &v[1],
                              &v[2], &v[3], &v[4], &v[5], &v[6], &used);
    bool finite = n == 8;
    for (int k = 0; finite && k < 7; ++k) finite = std::isfinite(v[k]);
    if (!finite) {
      std::fclose(f);
      return Error(Errc::kBadMetadata,
                   "replay: %s:%d: expected 'name x y z qw qx qy qz' with finite numbers", path,
                   lineno);
    }
    const double qn = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
    if (!(qn > 1e-9)) {
      std::fclose(f);
      return Error(Errc::kBadMetadata, "replay: %s:%d: zero quaternion", path, lineno);
    }
    for (int k = 0; k < 3; ++k) e.position[k] = v[k];
    for (int k = 0; k < 4; ++k) e.orientation[k] = v[3 + k] / qn;
    out->push_back(e);
  }
  std::fclose(f);
  APRT_ENSURE(out->size() > before, Errc::kBadMetadata, "replay: %s lists no frames", path);
  return ok();
}

}  // namespace aprt
