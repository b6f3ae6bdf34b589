#include "runtime/engine/ensemble_merge.h"

#include <cmath>

namespace aprt {

namespace {

// The rotation taking unit quaternion a to unit quaternion b as an axis-angle
// vector in a's frame, sign-free: 2 atan2(|v|, w) v / |v| of conj(a) * b
// (tools/aprt_tools/train_loss.py, rotation_error_vector).
void rotation_between(const double a[4], const double b[4], double out[3]) {
  double w = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  double v[3] = {a[0] * b[1] - b[0] * a[1] - (a[2] * b[3] - a[3] * b[2]),
                 a[0] * b[2] - b[0] * a[2] - (a[3] * b[1] - a[1] * b[3]),
                 a[0] * b[3] - b[0] * a[3] - (a[1] * b[2] - a[2] * b[1])};
  if (w < 0) {
    w = -w;
    for (double& x : v) x = -x;
  }
  const double n = std::fmax(std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]), 1e-12);
  const double angle = 2.0 * std::atan2(n, w);
  for (int i = 0; i < 3; ++i) out[i] = v[i] / n * angle;
}

bool unit(const double q[4], double out[4]) {
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(n > 1e-6)) return false;
  for (int i = 0; i < 4; ++i) out[i] = q[i] / n;
  return true;
}

}  // namespace

MergedOutputs merge_members(const float* raw, int n) noexcept {
  MergedOutputs m;
  if (n < 1 || n > kMaxEnsembleMembers) return m;
  const auto member = [raw](int i) { return raw + kNetworkOutputs * i; };
  // The reference sign: the member whose quaternion is largest.
  int ref = 0;
  double best = -1.0;
  for (int i = 0; i < n; ++i) {
    const float* q = member(i) + 3;
    const double norm2 =
        double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2] + double(q[3]) * q[3];
    if (norm2 > best) best = norm2, ref = i;
  }
  double sum[kNetworkOutputs] = {};
  for (int i = 0; i < n; ++i) {
    const float* o = member(i);
    const float* r = member(ref);
    const double dot =
        double(o[3]) * r[3] + double(o[4]) * r[4] + double(o[5]) * r[5] + double(o[6]) * r[6];
    const double sign = dot < 0 ? -1.0 : 1.0;
    for (int k = 0; k < kNetworkOutputs; ++k) sum[k] += (k >= 3 && k < 7 ? sign : 1.0) * o[k];
  }
  for (int k = 0; k < kNetworkOutputs; ++k) m.raw[k] = static_cast<float>(sum[k] / n);
  for (int a = 0; a < 3; ++a) {
    double var = 0.0;
    for (int i = 0; i < n; ++i) {
      const double d = double(member(i)[a]) - sum[a] / n;
      var += d * d;
    }
    m.position_sd[a] = std::sqrt(var / n);
  }
  const double mean_q[4] = {sum[3] / n, sum[4] / n, sum[5] / n, sum[6] / n};
  double merged[4];
  if (!unit(mean_q, merged)) return m;  // degenerate: decode_pose flags it
  double sq[3] = {};
  for (int i = 0; i < n; ++i) {
    const double q[4] = {member(i)[3], member(i)[4], member(i)[5], member(i)[6]};
    double qi[4], d[3];
    if (!unit(q, qi)) {
      for (double& x : sq) x = INFINITY;  // a member without a rotation: no confidence
      break;
    }
    rotation_between(merged, qi, d);
    for (int a = 0; a < 3; ++a) sq[a] += d[a] * d[a];
  }
  for (int a = 0; a < 3; ++a) m.rotation_sd[a] = std::sqrt(sq[a] / n);
  return m;
}

}  // namespace aprt
