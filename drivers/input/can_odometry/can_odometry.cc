#include "drivers/input/can_odometry/can_odometry.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <initializer_list>
#include <new>

#include "runtime/base/clock.h"

namespace aprt {
namespace {

// Beyond these no vehicle moves: a decoded value past them is a wrong DBC
// entry or an "invalid" code the DBC's range does not exclude.
constexpr double kMaxSpeedMps = 150.0;
constexpr double kMaxYawRateRadps = 60.0;
constexpr double kPi = 3.14159265358979323846;
constexpr int64_t kReopenEveryNs = 1000000000;
constexpr int64_t kAliveNs = 1000000000;

// "MESSAGE.SIGNAL" in the DBC, or an error that says what is there.
Expected<const can::DbcSignal*> find_signal(const can::Dbc& dbc, const std::string& path,
                                            const char* key, const std::string& origin,
                                            const can::DbcMessage** message) {
  const size_t dot = path.find('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == path.size()) {
    return Error(Errc::kInvalidArgument,
                 "can odometry: odometry.can.%s '%s' is not MESSAGE.SIGNAL (names as in %s)", key,
                 path.c_str(), origin.c_str());
  }
  const std::string msg = path.substr(0, dot), sig = path.substr(dot + 1);
  const can::DbcMessage* m = dbc.message(msg);
  if (!m) {
    std::string names;
    for (const auto& mm : dbc.messages) {
      if (names.size() > 200) {
        names += ", ...";
        break;
      }
      names += (names.empty() ? "" : ", ") + mm.name;
    }
    return Error(Errc::kNotFound,
                 "can odometry: %s has no message '%s' (odometry.can.%s); it has %s",
                 origin.c_str(), msg.c_str(), key, names.c_str());
  }
  const can::DbcSignal* s = m->signal(sig);
  if (!s) {
    std::string names;
    for (const auto& ss : m->signals) names += (names.empty() ? "" : ", ") + ss.name;
    return Error(Errc::kNotFound,
                 "can odometry: message %s in %s has no signal '%s' (odometry.can.%s); it has %s",
                 msg.c_str(), origin.c_str(), sig.c_str(), key,
                 names.empty() ? "none" : names.c_str());
  }
  if (s->multiplexor || s->mux_value >= 0) {
    return Error(Errc::kUnsupported,
                 "can odometry: signal %s is multiplexed (%s in %s); odometry signals must be in "
                 "every frame of their message",
                 path.c_str(), s->multiplexor ? "M" : "m<k>", origin.c_str());
  }
  *message = m;
  return s;
}

bool unit_is(const std::string& u, std::initializer_list<const char*> names) {
  for (const char* n : names) {
    if (u == n) return true;
  }
  return false;
}

}  // namespace

double speed_unit_scale(const std::string& u) {
  if (unit_is(u, {"m/s", "mps", "m/sec"})) return 1.0;
  if (unit_is(u, {"km/h", "kph", "kmh", "km/hr", "kmph"})) return 1.0 / 3.6;
  if (unit_is(u, {"mph", "mi/h"})) return 0.44704;
  return 0;
}

double yaw_rate_unit_scale(const std::string& u) {
  if (unit_is(u, {"rad/s", "radps", "rad/sec"})) return 1.0;
  if (unit_is(u, {"deg/s", "degps", "deg/sec", "\xC2\xB0/s", "dps"})) return kPi / 180.0;
  return 0;
}

Expected<CanOdometryDecoder> CanOdometryDecoder::create(const can::Dbc& dbc,
                                                        const CanOdometryOptions& o,
                                                        const std::string& origin) {
  const can::DbcMessage *speed_msg = nullptr, *yaw_msg = nullptr;
  auto speed = find_signal(dbc, o.speed, "speed", origin, &speed_msg);
  if (!speed) return speed.error();
  auto yaw = find_signal(dbc, o.yaw_rate, "yaw_rate", origin, &yaw_msg);
  if (!yaw) return yaw.error();
  CanOdometryDecoder d;
  d.speed_ = *speed.value();
  d.yaw_ = *yaw.value();
  d.speed_id_ = speed_msg->id;
  d.yaw_id_ = yaw_msg->id;
  d.speed_bytes_ = d.speed_.bytes_spanned();
  d.yaw_bytes_ = d.yaw_.bytes_spanned();
  const std::string su = o.speed_unit.empty() ? d.speed_.unit : o.speed_unit;
  const std::string yu = o.yaw_rate_unit.empty() ? d.yaw_.unit : o.yaw_rate_unit;
  d.speed_scale_ = speed_unit_scale(su);
  d.yaw_scale_ = yaw_rate_unit_scale(yu);
  if (d.speed_scale_ == 0) {
    return Error(Errc::kInvalidArgument,
                 "can odometry: %s's unit '%s' is not a speed aprt knows (m/s, km/h, mph); set "
                 "odometry.can.speed_unit to the unit its factor gives",
                 o.speed.c_str(), su.c_str());
  }
  if (d.yaw_scale_ == 0) {
    return Error(Errc::kInvalidArgument,
                 "can odometry: %s's unit '%s' is not a yaw rate aprt knows (rad/s, deg/s); set "
                 "odometry.can.yaw_rate_unit to the unit its factor gives",
                 o.yaw_rate.c_str(), yu.c_str());
  }
  if (o.yaw_rate_clockwise) d.yaw_scale_ = -d.yaw_scale_;
  if (o.max_pair_age_ms < 1) {
    return Error(Errc::kInvalidArgument, "can odometry: max_pair_age_ms %d must be >= 1",
                 o.max_pair_age_ms);
  }
  d.max_pair_age_ns_ = int64_t(o.max_pair_age_ms) * 1000000;
  d.description_ = o.speed + " [" + su + "] + " + o.yaw_rate + " [" + yu + "]" +
                   (o.yaw_rate_clockwise ? " (clockwise)" : "");
  return d;
}

bool CanOdometryDecoder::decode(const can::DbcSignal& s, int bytes, const can::Frame& f,
                                double scale, double* out) noexcept {
  if (f.len < bytes) {
    last_refusal_ = "frame shorter than its signal";
    return false;
  }
  const double v = s.physical(f.data, f.len);
  // The DBC's own range (where one is given) excludes the ECU's invalid codes.
  if (s.max > s.min && (v < s.min || v > s.max)) {
    last_refusal_ = "value outside the DBC's range (an invalid code?)";
    return false;
  }
  *out = v * scale;
  return true;
}

CanOdometryDecoder::Result CanOdometryDecoder::on_frame(const can::Frame& f, int64_t stamp_ns,
                                                        TwistSample* out) noexcept {
  const bool is_yaw = f.id == yaw_id_, is_speed = f.id == speed_id_;
  if (!is_yaw && !is_speed) return Result::kIgnored;
  if (is_yaw) {
    double w;
    if (!decode(yaw_, yaw_bytes_, f, yaw_scale_, &w)) {
      have_yaw_ = false;
      return Result::kRefused;
    }
    if (!(std::fabs(w) <= kMaxYawRateRadps)) {
      have_yaw_ = false;
      last_refusal_ = "yaw rate beyond 60 rad/s";
      return Result::kRefused;
    }
    yaw_value_ = w;
    yaw_stamp_ns_ = stamp_ns;
    have_yaw_ = true;
    if (!is_speed) return Result::kHeld;
  }
  double v;
  if (!decode(speed_, speed_bytes_, f, speed_scale_, &v)) return Result::kRefused;
  if (!(std::fabs(v) <= kMaxSpeedMps)) {
    last_refusal_ = "speed beyond 150 m/s";
    return Result::kRefused;
  }
  const int64_t age = stamp_ns - yaw_stamp_ns_;
  if (!have_yaw_ || age > max_pair_age_ns_ || age < -max_pair_age_ns_) {
    last_refusal_ = "no yaw rate within max_pair_age_ms of the speed";
    return Result::kRefused;
  }
  if (stamp_ns <= 0) {
    last_refusal_ = "frame without a receive time";
    return Result::kRefused;
  }
  *out = {stamp_ns, v, yaw_value_};
  return Result::kSample;
}

Expected<std::unique_ptr<CanTwistReader>> CanTwistReader::create(const CanOdometryOptions& o) {
  if (o.dbc.empty()) {
    return Error(Errc::kInvalidArgument,
                 "can odometry: odometry.can.dbc (the vehicle's DBC file) is required");
  }
  auto dbc = can::load_dbc(o.dbc);
  if (!dbc) return Error(dbc.error().code(), "can odometry: %s", dbc.error().message());
  auto dec = CanOdometryDecoder::create(dbc.value(), o, o.dbc);
  if (!dec) return dec.error();
  std::unique_ptr<CanTwistReader> r(new (std::nothrow) CanTwistReader(std::move(dec.value())));
  if (!r) return Error(Errc::kOutOfMemory, "can odometry: out of memory");
  const uint32_t ids[2] = {r->decoder_.speed_id(), r->decoder_.yaw_rate_id()};
  const int n = ids[0] == ids[1] ? 1 : 2;
  auto s = can::SocketCan::open(o.interface, false, true);
  if (s) {
    r->socket_ = std::move(s.value());
    r->bound_ = true;
  } else if (s.error().code() == Errc::kNotFound) {
    // Not there yet: read() on an unbound socket waits out its timeout, and
    // take() binds it once the interface appears.
    std::fprintf(stderr, "odometry: %s; retrying every second\n", s.error().message());
    r->socket_ = can::SocketCan::unbound(o.interface, false, true);
    if (!r->socket_) return Error(Errc::kOutOfMemory, "can odometry: out of memory");
    r->next_reopen_ns_ = monotonic_ns() + kReopenEveryNs;
  } else {
    return Error(s.error().code(), "odometry: %s", s.error().message());
  }
  if (Status st = r->socket_->set_filter(ids, n); !st) {
    return Error(st.error().code(), "odometry: %s", st.error().message());
  }
  return r;
}

void CanTwistReader::try_reopen(int64_t now_ns) noexcept {
  if (now_ns < next_reopen_ns_) return;
  next_reopen_ns_ = now_ns + kReopenEveryNs;
  if (socket_->reopen()) {
    bound_ = true;
    ++reopened_;
  }
}

int CanTwistReader::take(TwistSample* out, int max, int64_t timeout_ns) {
  int n = 0;
  int wait_ms = int(timeout_ns / 1000000);
  while (n < max) {
    if (!bound_) {
      // Nothing to read: wait out the timeout, then try the interface again.
      if (wait_ms > 0) {
        timespec ts{wait_ms / 1000, (wait_ms % 1000) * 1000000L};
        nanosleep(&ts, nullptr);
      }
      try_reopen(monotonic_ns());
      return n;
    }
    can::Frame f;
    int64_t stamp = 0;
    const int r = socket_->read(&f, wait_ms, &stamp);
    wait_ms = 0;  // the rest of a burst without waiting
    if (r == 0) break;
    if (r < 0) {
      // The interface went away (ENODEV) or down (ENETDOWN): bind again
      // once it is back; the gap shows as a new odometry epoch.
      bound_ = false;
      next_reopen_ns_ = monotonic_ns() + kReopenEveryNs;
      break;
    }
    if (f.id & can::SocketCan::kErrorFrameFlag) continue;
    TwistSample s;
    switch (decoder_.on_frame(f, stamp, &s)) {
      case CanOdometryDecoder::Result::kSample:
        out[n++] = s;
        ++stats_.received;
        last_frame_ns_.store(monotonic_ns(), std::memory_order_relaxed);
        break;
      case CanOdometryDecoder::Result::kHeld:
        last_frame_ns_.store(monotonic_ns(), std::memory_order_relaxed);
        break;
      case CanOdometryDecoder::Result::kRefused: ++stats_.refused; break;
      case CanOdometryDecoder::Result::kIgnored: break;
    }
  }
  return n;
}

int CanTwistReader::publishers() const {
  const int64_t last = last_frame_ns_.load(std::memory_order_relaxed);
  return last != 0 && monotonic_ns() - last < kAliveNs ? 1 : 0;
}

}  // namespace aprt
