#include "runtime/pose/pose_gate.h"

#include <cmath>

namespace aprt {
namespace {

constexpr double kChi2Sqrt95 = 2.447746830680816;  // sqrt(chi^2_2(0.95)): the 95 % ellipse
constexpr double kZ95 = 1.959963984540054;

}  // namespace

bool confident(const PoseEstimate& e, double max_radius_m, double max_yaw_deg) noexcept {
  if (!e.has_sigma) return true;
  const double r = kChi2Sqrt95 * std::fmax(e.sigma_position_m[0], e.sigma_position_m[1]);
  const double yaw_interval = kZ95 * e.sigma_rotation_rad[2] * 180.0 / kPiRad;
  return r <= max_radius_m && yaw_interval <= max_yaw_deg;
}

void PoseGate::Track::add(double tn, double xn, double yn, double yawn) noexcept {
  // Yaw unwrapped against the newest: the least-squares line sees no 2 pi steps.
  if (size > 0) yawn = last_yaw() + wrap_angle(yawn - last_yaw());
  t[head] = tn;
  x[head] = xn;
  y[head] = yn;
  yaw[head] = yawn;
  head = (head + 1) % kWindow;
  if (size < kWindow) ++size;
  ++count;
  rejected = 0;
}

void PoseGate::Track::predict(double tq, double max_speed, double* px, double* py,
                              double* pyaw) const noexcept {
  const int newest = (head + kWindow - 1) % kWindow;
  // Least squares over the window's estimates within kWindowS of the newest.
  double n = 0, st = 0, stt = 0, sx = 0, sy = 0, sa = 0, stx = 0, sty = 0, sta = 0;
  for (int i = 0; i < size; ++i) {
    const int k = (newest - i + kWindow) % kWindow;
    const double dt = t[k] - t[newest];
    if (-dt > kWindowS) break;
    n += 1;
    st += dt;
    stt += dt * dt;
    sx += x[k];
    sy += y[k];
    sa += yaw[k];
    stx += dt * x[k];
    sty += dt * y[k];
    sta += dt * yaw[k];
  }
  const double den = n * stt - st * st;
  double vx = 0, vy = 0, va = 0;
  double ax = x[newest], ay = y[newest], aa = yaw[newest];
  if (n >= 3 && den > 1e-9 && stt / n - (st / n) * (st / n) > 0.01) {  // >= ~0.1 s of spread
    vx = (n * stx - st * sx) / den;
    vy = (n * sty - st * sy) / den;
    va = (n * sta - st * sa) / den;
    ax = (sx - vx * st) / n;  // the line's value at the newest estimate's time
    ay = (sy - vy * st) / n;
    aa = (sa - va * st) / n;
    const double speed = std::sqrt(vx * vx + vy * vy);
    if (speed > max_speed) {
      vx *= max_speed / speed;
      vy *= max_speed / speed;
    }
  }
  const double dt = tq - t[newest];
  *px = ax + vx * dt;
  *py = ay + vy * dt;
  *pyaw = aa + va * dt;
}

bool PoseGate::consistent(const Track& k, double t, double x, double y, double yaw) const noexcept {
  if (k.size == 0) return true;
  double px, py, pyaw;
  k.predict(t, p_.max_speed_mps, &px, &py, &pyaw);
  const double since = t - k.last_t();
  const double gate = p_.gate_m + p_.gate_growth_mps * (since > 0 ? since : 0);
  const double d = std::hypot(x - px, y - py);
  return d <= gate && std::fabs(wrap_angle(yaw - pyaw)) <= p_.gate_deg * kPiRad / 180.0;
}

bool PoseGate::motion(double t0, double t1, double* dx, double* dy, double* dyaw) const noexcept {
  *dx = *dy = *dyaw = 0;
  if (!tracking() || track_.size == 0) return false;
  double x0, y0, a0, x1, y1, a1;
  track_.predict(t0, p_.max_speed_mps, &x0, &y0, &a0);
  track_.predict(t1, p_.max_speed_mps, &x1, &y1, &a1);
  *dx = x1 - x0;
  *dy = y1 - y0;
  *dyaw = a1 - a0;
  return true;
}

void PoseGate::reset() noexcept {
  track_.clear();
  candidate_.clear();
  have_prev_ = false;
}

// The jump from the reference pose: with the gate on, the last pose that went
// out valid (so a run of wrong estimates never becomes the reference); with
// it off, the last plausible one (not non-finite, out of bounds, a jump, or a
// fusion without quorum).
uint32_t PoseGate::jump(const PoseEstimate& e, double t, uint32_t flags) noexcept {
  if (!have_prev_ || p_.max_jump_m <= 0 || (flags & kPoseNonFinite)) return 0;
  double d = 0;
  for (int k = 0; k < 3; ++k) d += (e.position[k] - prev_[k]) * (e.position[k] - prev_[k]);
  const double dt = t - prev_t_;
  return std::sqrt(d) > p_.max_jump_m + p_.max_speed_mps * (dt > 0 ? dt : 0) ? kPoseJump : 0;
}

void PoseGate::remember(const PoseEstimate& e, double t) noexcept {
  for (int k = 0; k < 3; ++k) prev_[k] = e.position[k];
  prev_t_ = t;
  have_prev_ = true;
}

uint32_t PoseGate::check(const PoseEstimate& e, double t, uint32_t flags) noexcept {
  const uint32_t out = gate(e, t, flags);
  constexpr uint32_t kImplausible = kPoseNonFinite | kPoseOutOfBounds | kPoseNoQuorum | kPoseJump;
  if (p_.enabled ? (flags | out) == 0 : !((flags | out) & kImplausible)) remember(e, t);
  return out;
}

uint32_t PoseGate::gate(const PoseEstimate& e, double t, uint32_t flags) noexcept {
  uint32_t out = jump(e, t, flags);
  if (!p_.enabled) return out;
  bool usable = (flags | out) == 0;
  if (!confident(e, p_.max_position_radius_m, p_.max_yaw_interval_deg)) {
    out |= kPoseUncertain;
    usable = false;
  }
  const double x = e.position[0], y = e.position[1], yaw = quaternion_yaw(e.orientation);
  if (!usable) {
    if (track_.count > 0 && ++track_.rejected >= p_.lost_after) track_.clear();
    return out | (tracking() ? kPoseInconsistent : kPoseUnconfirmed);
  }
  if (track_.count > 0 && consistent(track_, t, x, y, yaw)) {
    track_.add(t, x, y, yaw);
    candidate_.clear();
    return tracking() ? out : out | kPoseUnconfirmed;
  }
  // Refused by the track (or there is none): it may start, or continue, a
  // candidate, which becomes the track once confirmed -- but only when no
  // live track holds (a track survives `lost_after` refusals in a row).
  if (track_.count > 0) ++track_.rejected;
  if (track_.count > 0 && track_.rejected >= p_.lost_after) track_.clear();
  if (!consistent(candidate_, t, x, y, yaw)) candidate_.clear();
  candidate_.add(t, x, y, yaw);
  if (track_.count == 0 && candidate_.count >= p_.confirm) {
    track_ = candidate_;
    candidate_.clear();
    return out;
  }
  if (track_.count == 0 && candidate_.count < p_.confirm) {
    // Not yet confirmed: the candidate is the track-to-be.
    return out | kPoseUnconfirmed;
  }
  return out | (tracking() ? kPoseInconsistent : kPoseUnconfirmed);
}

}  // namespace aprt
