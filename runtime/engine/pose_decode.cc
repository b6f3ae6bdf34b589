#include "runtime/engine/pose_decode.h"

#include <cmath>
#include <cstdio>
#include <cstring>

namespace aprt {

PoseEstimate decode_pose(const float raw[7], const ModelMeta& meta, float bounds_margin) noexcept {
  PoseEstimate p;
  for (int i = 0; i < 7; ++i) {
    if (!std::isfinite(raw[i])) p.flags |= kPoseNonFinite;
  }
  for (int i = 0; i < 3; ++i) {
    const double lo = meta.pose_min[i], hi = meta.pose_max[i];
    const double extent = hi - lo;
    p.position[i] = lo + double(raw[i]) * extent;
    const double margin = extent * bounds_margin;
    if (!(p.position[i] >= lo - margin && p.position[i] <= hi + margin)) {
      p.flags |= kPoseOutOfBounds;
    }
  }
  double q[4] = {raw[3], raw[4], raw[5], raw[6]};
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  p.raw_quat_norm = static_cast<float>(n);
  if (!(n > 1e-6)) {
    p.flags |= kPoseQuatDegenerate;
    return p;  // orientation stays identity, flagged
  }
  if (n < 0.5 || n > 2.0) p.flags |= kPoseQuatNorm;
  const double s = (q[0] < 0.0 ? -1.0 : 1.0) / n;
  for (int i = 0; i < 4; ++i) p.orientation[i] = q[i] * s;
  return p;
}

const char* pose_flags_text(uint32_t flags, char* buf, int size) noexcept {
  if (size <= 0) return buf;
  if (flags == 0) {
    std::snprintf(buf, size, "ok");
    return buf;
  }
  static const char* const kNames[] = {"non-finite", "quat-degenerate", "quat-norm",
                                       "out-of-bounds"};
  int used = 0;
  buf[0] = '\0';
  for (int bit = 0; bit < 4; ++bit) {
    if (!(flags & (1u << bit))) continue;
    used += std::snprintf(buf + used, size > used ? size - used : 0, "%s%s", used ? "," : "",
                          kNames[bit]);
  }
  return buf;
}

}  // namespace aprt
