#include "runtime/pose/sensor_fusion.h"

#include <cmath>

#include "runtime/base/angles.h"
#include "runtime/engine/pose_decode.h"
#include "runtime/pose/pose_flags.h"

namespace aprt {
namespace {

double yaw_of(const Eigen::Quaterniond& q) {
  return yaw_of_quaternion(q.w(), q.x(), q.y(), q.z());
}

}  // namespace

const char* fused_from_name(FusedFrom f) {
  switch (f) {
    case FusedFrom::kNone: return "none";
    case FusedFrom::kPrimary: return "own";
    case FusedFrom::kCompanion: return "companion";
    case FusedFrom::kBoth: return "both";
  }
  return "?";
}

SensorFusionResult fuse_sensors(const SensorEstimate& a, const SensorEstimate& b,
                                const SensorFusionParams& p) noexcept {
  SensorFusionResult r;
  if (a.present && b.present) {
    r.distance_m = std::hypot(a.position.x() - b.position.x(), a.position.y() - b.position.y());
    r.yaw_diff_rad = std::fabs(wrap_angle(yaw_of(a.orientation) - yaw_of(b.orientation)));
  }
  const auto take = [&](const SensorEstimate& e, FusedFrom from) {
    r.pose = e;
    r.from = from;
    return r;
  };
  if (a.usable() && b.usable()) {
    r.disagree = r.distance_m > p.max_position_spread_m || r.yaw_diff_rad > p.max_yaw_spread_rad;
    if (r.disagree) {
      if (a.valid_for_s >= b.valid_for_s + p.min_lead_s) return take(a, FusedFrom::kPrimary);
      if (b.valid_for_s >= a.valid_for_s + p.min_lead_s) return take(b, FusedFrom::kCompanion);
      r.pose = a;
      r.pose.flags = kPoseNoQuorum;
      r.from = FusedFrom::kPrimary;
      return r;
    }
    SensorEstimate& f = r.pose;
    f = a;
    for (int k = 0; k < 3; ++k) {
      const double va = a.var_position[k], vb = b.var_position[k];
      const double wb = va / (va + vb);  // the weight of b: the smaller its variance, the larger
      f.position[k] = a.position[k] + wb * (b.position[k] - a.position[k]);
      f.var_position[k] = va * vb / (va + vb);
    }
    const double wb = a.var_yaw / (a.var_yaw + b.var_yaw);
    Eigen::Quaterniond qb = b.orientation;
    if (a.orientation.dot(qb) < 0) qb.coeffs() = -qb.coeffs();
    f.orientation = a.orientation.slerp(wb, qb).normalized();
    f.var_yaw = a.var_yaw * b.var_yaw / (a.var_yaw + b.var_yaw);
    f.valid_for_s = std::fmax(a.valid_for_s, b.valid_for_s);
    r.from = FusedFrom::kBoth;
    return r;
  }
  if (a.usable() || b.usable()) {
    const bool a_alone = a.usable();
    const SensorEstimate& one = a_alone ? a : b;
    const SensorEstimate& other = a_alone ? b : a;
    const FusedFrom from = a_alone ? FusedFrom::kPrimary : FusedFrom::kCompanion;
    constexpr uint32_t kNoEstimate = kPoseNonFinite | kPoseQuatDegenerate | kPoseQuatNorm |
                                     kPoseOutOfBounds | kPoseSparseScan | kPoseStaleFrame;
    if (p.cross_check && other.present && !(other.flags & kNoEstimate) &&
        one.valid_for_s < p.min_lead_s &&
        (r.distance_m > p.max_position_spread_m || r.yaw_diff_rad > p.max_yaw_spread_rad)) {
      take(one, from);
      r.pose.flags = kPoseNoQuorum;
      return r;
    }
    return take(one, from);
  }
  // Neither may go out: the one that states the smaller horizontal variance
  // is shown (flagged).
  const auto horizontal = [](const SensorEstimate& e) {
    return std::fmax(e.var_position[0], e.var_position[1]);
  };
  if (b.present && (!a.present || horizontal(b) < horizontal(a)))
    return take(b, FusedFrom::kCompanion);
  return take(a, FusedFrom::kPrimary);
}

}  // namespace aprt
