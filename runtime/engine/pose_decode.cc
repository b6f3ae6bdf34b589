#include "runtime/engine/pose_decode.h"

#include <cmath>
#include <cstring>

#include "runtime/engine/ensemble_merge.h"

namespace aprt {

namespace {

// Laplace scale b = exp(s) has variance 2 b^2; s is clamped to the range the
// trainer clamps it to (tools/aprt_tools/train_loss.py).
double laplace_sigma(float s) {
  const double c = s < -14.0f ? -14.0 : (s > 6.0f ? 6.0 : double(s));
  return std::sqrt(2.0) * std::exp(c);
}

}  // namespace

PoseEstimate decode_pose(const float* raw_outputs, const ModelMeta& meta,
                         float bounds_margin) noexcept {
  PoseEstimate p;
  // An ensemble's members merged first (FORMAT.md 1.5): one network's
  // outputs, and how far the members are apart.
  MergedOutputs merged;
  const float* raw = raw_outputs;
  if (meta.member_outputs > 0) {
    merged = merge_members(raw_outputs, int(meta.member_outputs));
    raw = merged.raw;
  }
  if (meta.has_uncertainty) {
    bool finite = true;
    for (int i = 7; i < 13; ++i) finite = finite && std::isfinite(raw[i]);
    for (int i = 0; i < 3; ++i) {
      finite =
          finite && std::isfinite(merged.position_sd[i]) && std::isfinite(merged.rotation_sd[i]);
    }
    if (!finite) {
      p.flags |= kPoseNoConfidence;
    } else {
      p.has_sigma = true;
      for (int i = 0; i < 3; ++i) {
        // The members' spread joins the network's own in quadrature, before
        // the calibration scale (a variance of a mixture: Lakshminarayanan
        // et al. 2017); zero for one network.
        const double extent = double(meta.pose_max[i] - meta.pose_min[i]);
        const double own = laplace_sigma(raw[7 + i]);
        const double spread = merged.position_sd[i];
        p.sigma_position_m[i] =
            meta.uncertainty_scale[0] * std::sqrt(own * own + spread * spread) * extent;
        const double own_r = laplace_sigma(raw[10 + i]);
        const double spread_r = merged.rotation_sd[i];
        p.sigma_rotation_rad[i] =
            meta.uncertainty_scale[1] * std::sqrt(own_r * own_r + spread_r * spread_r);
      }
    }
  }
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

}  // namespace aprt
