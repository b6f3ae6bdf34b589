#include "runtime/pose/pose_filter.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "runtime/base/angles.h"
#include "runtime/pose/pose_flags.h"

namespace aprt {
namespace {

constexpr double kChi2Sqrt95 = 2.447746830680816;  // sqrt(chi^2_2(0.95)): the 95 % ellipse
constexpr double kZ95 = 1.959963984540054;

using Mat3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
using Mat5 = Eigen::Matrix<double, 5, 5, Eigen::RowMajor>;
using Mat35 = Eigen::Matrix<double, 3, 5, Eigen::RowMajor>;

// What an estimate measures of the state: the pose plus the place's bias.
Mat35 measurement() noexcept {
  Mat35 H = Mat35::Zero();
  H(0, 0) = H(1, 1) = H(2, 2) = 1;
  H(0, 3) = H(1, 4) = 1;
  return H;
}

// The 95 % radius of a horizontal covariance [[a, b], [b, c]].
double radius95(double a, double b, double c) noexcept {
  const double lmax = 0.5 * (a + c) + std::sqrt(0.25 * (a - c) * (a - c) + b * b);
  return kChi2Sqrt95 * std::sqrt(std::fmax(lmax, 0.0));
}

}  // namespace

const char* PoseFilter::use_name(Use u) {
  switch (u) {
    case Use::kNone: return "no usable estimate";
    case Use::kAccepted: return "estimate taken";
    case Use::kRefused: return "estimate refused";
    case Use::kStarted: return "started";
    case Use::kTookOver: return "taken over";
  }
  return "?";
}

void PoseFilter::reset() noexcept {
  fix_ = State{};
  candidate_ = State{};
  refused_ = 0;
}

PoseFilter::State PoseFilter::start(const PlanarPose& z) const noexcept {
  State k;
  k.s[0] = z.x;
  k.s[1] = z.y;
  k.s[2] = z.yaw;
  Eigen::Map<Mat5> P(k.P);
  P(0, 0) = z.sigma_x * z.sigma_x;
  P(1, 1) = z.sigma_y * z.sigma_y;
  P(2, 2) = z.sigma_yaw * z.sigma_yaw;
  // The estimate is the pose plus the place's bias plus its own noise. Taken
  // as the pose with no bias, the pose is off by the bias plus the noise and
  // the bias by minus the bias: hence the negative cross terms.
  const double b2 = p_.place_sigma_m * p_.place_sigma_m;
  for (int i = 0; i < 2; ++i) {
    P(i, i) += b2;
    P(3 + i, 3 + i) = b2;
    P(i, 3 + i) = P(3 + i, i) = -b2;
  }
  k.count = 1;
  return k;
}

// x' = x + R(yaw) (dx, dy), yaw' = yaw + dyaw; the covariance through the
// Jacobian, plus the odometry's own error for the step. The place bias
// decays with the distance driven and is renewed by as much.
void PoseFilter::predict(State* k, const PlanarMotion& m) const noexcept {
  const double c = std::cos(k->s[2]), s = std::sin(k->s[2]);
  k->s[0] += c * m.dx - s * m.dy;
  k->s[1] += s * m.dx + c * m.dy;
  k->s[2] = wrap_angle(k->s[2] + m.dyaw);
  Mat5 F = Mat5::Identity();
  F(0, 2) = -s * m.dx - c * m.dy;
  F(1, 2) = c * m.dx - s * m.dy;
  Mat5 Q = Mat5::Zero();
  if (p_.place_sigma_m > 0) {
    const double phi = std::exp(-std::fabs(m.distance_m) / p_.place_length_m);
    k->s[3] *= phi;
    k->s[4] *= phi;
    F(3, 3) = F(4, 4) = phi;
    Q(3, 3) = Q(4, 4) = p_.place_sigma_m * p_.place_sigma_m * (1.0 - phi * phi);
  }
  Eigen::Map<Mat5> P(k->P);
  const double sd = p_.distance_noise * m.distance_m;
  const double sy =
      (p_.yaw_noise_deg_per_m * m.distance_m + p_.yaw_rate_noise_dps * m.dt_s) * kPiRad / 180.0;
  Q(0, 0) = Q(1, 1) = sd * sd;
  Q(2, 2) = sy * sy;
  const Mat5 next = F * P * F.transpose() + Q;
  P = next;
}

double PoseFilter::innovation(const State& k, const PlanarPose& z, bool update,
                              State* out) const noexcept {
  const Eigen::Map<const Mat5> P(k.P);
  const Mat35 H = measurement();
  Eigen::Vector3d v(z.x - k.s[0] - k.s[3], z.y - k.s[1] - k.s[4], wrap_angle(z.yaw - k.s[2]));
  const Eigen::Matrix<double, 3, 5> HP = H * P;
  Mat3 S = HP * H.transpose();
  S(0, 0) += z.sigma_x * z.sigma_x;
  S(1, 1) += z.sigma_y * z.sigma_y;
  S(2, 2) += z.sigma_yaw * z.sigma_yaw;
  const Eigen::LDLT<Mat3> ldlt(S);
  if (ldlt.info() != Eigen::Success) return INFINITY;
  const Eigen::Vector3d w = ldlt.solve(v);
  const double d2 = v.dot(w);
  if (!update) return std::isfinite(d2) ? d2 : INFINITY;
  *out = k;
  // K = P H' S^-1 (S symmetric): the state moves by K v = (HP)' w, the
  // covariance shrinks by K HP; symmetrised against rounding.
  const Eigen::Matrix<double, 5, 3> K = ldlt.solve(HP).transpose();
  const Eigen::Matrix<double, 5, 1> ds = HP.transpose() * w;
  out->s[0] += ds[0];
  out->s[1] += ds[1];
  out->s[2] = wrap_angle(out->s[2] + ds[2]);
  out->s[3] += ds[3];
  out->s[4] += ds[4];
  Mat5 Pn = P - K * HP;
  Pn = 0.5 * (Pn + Pn.transpose());
  Eigen::Map<Mat5>(out->P) = Pn;
  out->count = k.count + 1;
  if (p_.disagreement_frames > 0) {
    // A running mean over the first estimates, then exponential.
    const double a = 1.0 / double(std::min(out->count - 1, p_.disagreement_frames));
    out->d[0] += a * (v[0] - out->d[0]);
    out->d[1] += a * (v[1] - out->d[1]);
  }
  return d2;
}

PoseFilter::Output PoseFilter::output(const State& k, uint32_t flags) const noexcept {
  Output o;
  o.fix = true;
  o.pose.x = k.s[0];
  o.pose.y = k.s[1];
  o.pose.yaw = k.s[2];
  // Validity takes the filter's own covariance; the published one scales its
  // position part (the estimates' stated sigmas overstate the errors of the
  // ones taken). Both add the estimates' mean disagreement with the filter,
  // an offset measured in metres, unscaled (zero unless disagreement_frames).
  const double s2 = p_.position_sigma_scale * p_.position_sigma_scale;
  const double dxx = k.d[0] * k.d[0], dxy = k.d[0] * k.d[1], dyy = k.d[1] * k.d[1];
  const Eigen::Map<const Mat5> P(k.P);
  const double xx = P(0, 0) * s2 + dxx, xy = P(0, 1) * s2 + dxy, yy = P(1, 1) * s2 + dyy;
  o.pose.sigma_x = std::sqrt(xx);
  o.pose.sigma_y = std::sqrt(yy);
  o.pose.sigma_yaw = std::sqrt(P(2, 2));
  o.cov_xy = xy;
  const double yaw95 = kZ95 * o.pose.sigma_yaw * 180.0 / kPiRad;
  const double own95 = radius95(P(0, 0) + dxx, P(0, 1) + dxy, P(1, 1) + dyy);
  if (!(own95 <= p_.max_radius_m) || !(yaw95 <= p_.max_yaw_deg)) flags |= kPoseUncertain;
  o.radius95_m = radius95(xx, xy, yy);
  o.yaw95_deg = yaw95;
  o.flags = flags;
  return o;
}

PoseFilter::Output PoseFilter::step(const PlanarMotion* motion,
                                    const PlanarPose* estimate) noexcept {
  if (!motion) {
    // Without the motion since the last step nothing carries over.
    reset();
    Output o;
    if (estimate) o.pose = *estimate;
    o.flags = kPoseNoOdometry | kPoseUnconfirmed;
    return o;
  }
  if (fix_.count > 0) predict(&fix_, *motion);
  if (candidate_.count > 0) predict(&candidate_, *motion);
  Use use = Use::kNone;
  if (estimate) {
    // The estimate as the filter weighs it (an unconfirmed output below
    // still carries the model's own sigma).
    PlanarPose z = *estimate;
    z.sigma_x *= p_.estimate_sigma_scale;
    z.sigma_y *= p_.estimate_sigma_scale;
    if (fix_.count > 0) {
      State next;
      if (innovation(fix_, z, false, nullptr) <= p_.gate_chi2) {
        (void)innovation(fix_, z, true, &next);
        fix_ = next;
        refused_ = 0;
        candidate_ = State{};
        use = Use::kAccepted;
      } else {
        ++refused_;
        use = Use::kRefused;
      }
    }
    if (fix_.count == 0 || use == Use::kRefused) {
      // A run of estimates that agree with each other along the odometry:
      // the fix to be, or the one that takes over a fix refusing everything.
      State next;
      if (candidate_.count > 0 && innovation(candidate_, z, false, nullptr) <= p_.gate_chi2) {
        (void)innovation(candidate_, z, true, &next);
        candidate_ = next;
      } else {
        candidate_ = start(z);
      }
      if (candidate_.count >= p_.confirm && (fix_.count == 0 || refused_ >= p_.take_over_after)) {
        use = fix_.count == 0 ? Use::kStarted : Use::kTookOver;
        fix_ = candidate_;
        candidate_ = State{};
        refused_ = 0;
      }
    }
  }
  if (fix_.count > 0) {
    const Eigen::Map<const Mat5> P(fix_.P);
    if (radius95(P(0, 0), P(0, 1), P(1, 1)) > p_.lost_radius_m) fix_ = State{};
  }
  Output o;
  if (fix_.count > 0) {
    o = output(fix_, 0);
  } else {
    if (estimate) o.pose = *estimate;
    o.flags = kPoseUnconfirmed;
  }
  o.use = use;
  o.refused = refused_;
  return o;
}

}  // namespace aprt
