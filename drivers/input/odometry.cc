#include "drivers/input/odometry.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "runtime/base/check.h"
#include "runtime/base/file_io.h"
#include "runtime/base/text_lines.h"

namespace aprt {
namespace {

constexpr uint64_t kMaxOdometryBytes = 256ull << 20;
constexpr double kMaxSpeedMps = 150.0;  // beyond any road vehicle: a unit or parsing error
// Far beyond a road vehicle (~1.5 rad/s), but a synthetic drive sampled every
// metre at 25 Hz turns up to 90 degrees between two frames (~39 rad/s).
constexpr double kMaxYawRateRadps = 60.0;

}  // namespace

Expected<OdometrySeries> OdometrySeries::from_samples(std::vector<OdometrySample> samples,
                                                      const char* what) {
  APRT_ENSURE(!samples.empty(), Errc::kBadMetadata, "%s: no odometry samples", what);
  for (size_t i = 0; i < samples.size(); ++i) {
    const OdometrySample& s = samples[i];
    APRT_ENSURE(
        std::isfinite(s.t_s) && std::isfinite(s.speed_mps) && std::isfinite(s.yaw_rate_radps),
        Errc::kBadMetadata, "%s: sample %zu is not finite", what, i);
    APRT_ENSURE(i == 0 || s.t_s > samples[i - 1].t_s, Errc::kBadMetadata,
                "%s: sample %zu at %g s is not after the previous one's %g s", what, i, s.t_s,
                samples[i - 1].t_s);
  }
  OdometrySeries out;
  out.samples_ = std::move(samples);
  return out;
}

Expected<OdometrySeries> OdometrySeries::parse(std::string_view text, const char* path) {
  std::vector<OdometrySample> samples;
  double last = -INFINITY;
  Status st = each_text_line(text, "odometry", path, true, [&](char* line, int lineno) -> Status {
    char* f[3];
    APRT_ENSURE(split_fields(line, f, 3) == 3, Errc::kBadMetadata,
                "odometry: %s:%d: expected 'seconds speed_mps yaw_rate_radps'", path, lineno);
    OdometrySample s;
    APRT_ENSURE(parse_finite(f[0], &s.t_s) && parse_finite(f[1], &s.speed_mps) &&
                    parse_finite(f[2], &s.yaw_rate_radps),
                Errc::kBadMetadata, "odometry: %s:%d: not three finite numbers", path, lineno);
    APRT_ENSURE(s.t_s > last, Errc::kBadMetadata,
                "odometry: %s:%d: %g s is not after the previous sample's %g s", path, lineno,
                s.t_s, last);
    APRT_ENSURE(std::fabs(s.speed_mps) <= kMaxSpeedMps, Errc::kBadMetadata,
                "odometry: %s:%d: speed %g m/s is beyond %g (not metres per second?)", path, lineno,
                s.speed_mps, kMaxSpeedMps);
    APRT_ENSURE(std::fabs(s.yaw_rate_radps) <= kMaxYawRateRadps, Errc::kBadMetadata,
                "odometry: %s:%d: yaw rate %g rad/s is beyond %g (degrees, not radians?)", path,
                lineno, s.yaw_rate_radps, kMaxYawRateRadps);
    last = s.t_s;
    samples.push_back(s);
    return ok();
  });
  if (!st) return st.error();
  APRT_ENSURE(!samples.empty(), Errc::kBadMetadata, "odometry: %s has no samples", path);
  return from_samples(std::move(samples), path);
}

Expected<OdometrySeries> OdometrySeries::load(const char* path) {
  std::string text;
  if (Status s = read_input_file(path, kMaxOdometryBytes, "odometry", &text); !s) return s.error();
  return parse(text, path);
}

namespace {

// base_link driven at speed v and yaw rate w for h seconds from `r` (its
// pose in the odometry frame): an arc, a line when straight.
void advance(OdometryReading* r, double v, double w, double h) noexcept {
  if (std::fabs(w * h) < 1e-9) {
    r->x += v * h * std::cos(r->yaw);
    r->y += v * h * std::sin(r->yaw);
  } else {
    r->x += v / w * (std::sin(r->yaw + w * h) - std::sin(r->yaw));
    r->y += v / w * (std::cos(r->yaw) - std::cos(r->yaw + w * h));
  }
  r->yaw += w * h;
  r->distance_m += std::fabs(v) * h;
  r->t_s += h;
}

}  // namespace

void OdometryTrack::add(const OdometrySample& s) noexcept {
  OdometryReading r;
  r.valid = true;
  r.t_s = s.t_s;
  if (size_ > 0) {
    const Entry& last = e_[(head_ + kCapacity - 1) % kCapacity];
    const double h = s.t_s - last.s.t_s;
    if (!(h > 0)) {
      if (h == 0) return;  // the same stamp again
      ++epoch_;            // the clock went back
    } else if (h > OdometrySeries::kMaxGapS) {
      ++epoch_;  // silent too long: what happened in between is not known
    } else {
      r = last.r;
      advance(&r, last.s.speed_mps, last.s.yaw_rate_radps, h);
      r.t_s = s.t_s;
    }
  }
  r.epoch = epoch_;
  e_[head_] = {s, r};
  head_ = (head_ + 1) % kCapacity;
  if (size_ < kCapacity) ++size_;
}

OdometryReading OdometryTrack::at(double t_s) const noexcept {
  // Newest first: a frame's time is usually within the last few samples.
  for (int i = 0; i < size_; ++i) {
    const Entry& e = e_[(head_ + kCapacity - 1 - i) % kCapacity];
    if (e.s.t_s > t_s) continue;
    const double h = t_s - e.s.t_s;
    if (h > OdometrySeries::kMaxGapS) return {};
    if (i > 0 && e_[(head_ + kCapacity - i) % kCapacity].r.epoch != e.r.epoch) {
      // t falls in a gap the next sample's new epoch began after.
      return {};
    }
    OdometryReading r = e.r;
    advance(&r, e.s.speed_mps, e.s.yaw_rate_radps, h);
    return r;
  }
  return {};  // older than everything kept
}

bool motion_between(const OdometryReading& a, const OdometryReading& b,
                    PlanarMotion* out) noexcept {
  *out = PlanarMotion{};
  if (!a.valid || !b.valid || a.epoch != b.epoch || b.t_s < a.t_s) return false;
  const double c = std::cos(a.yaw), s = std::sin(a.yaw);
  const double dx = b.x - a.x, dy = b.y - a.y;
  out->dx = c * dx + s * dy;
  out->dy = -s * dx + c * dy;
  out->dyaw = b.yaw - a.yaw;
  out->distance_m = b.distance_m - a.distance_m;
  out->dt_s = b.t_s - a.t_s;
  return true;
}

bool OdometrySeries::motion(double t0, double t1, PlanarMotion* out) const noexcept {
  *out = PlanarMotion{};
  if (samples_.empty() || !(t1 >= t0) || t0 < samples_.front().t_s) return false;
  // The sample holding at t0: the last one at or before it.
  auto it = std::upper_bound(samples_.begin(), samples_.end(), t0,
                             [](double t, const OdometrySample& s) { return t < s.t_s; });
  size_t k = size_t(it - samples_.begin()) - 1;
  if (t0 - samples_[k].t_s > kMaxGapS) return false;
  // base_link's pose in its own frame at t0, driven piece by piece.
  OdometryReading r;
  r.t_s = t0;
  while (r.t_s < t1) {
    const OdometrySample& s = samples_[k];
    const double next = k + 1 < samples_.size() ? samples_[k + 1].t_s : INFINITY;
    const double end = std::min(t1, next);
    if (end - s.t_s > kMaxGapS) return false;  // held too long: the bus was silent
    advance(&r, s.speed_mps, s.yaw_rate_radps, end - r.t_s);
    r.t_s = end;
    if (end >= next) ++k;
  }
  out->dx = r.x;
  out->dy = r.y;
  out->dyaw = r.yaw;
  out->distance_m = r.distance_m;
  out->dt_s = t1 - t0;
  return true;
}

}  // namespace aprt
