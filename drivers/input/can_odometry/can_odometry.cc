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

// "MESSAGE.SIGNAL" in the DBC, or an error that says what is there.
Expected<CanOdometryDecoder::Channel> CanOdometryDecoder::locate(const can::Dbc& dbc,
                                                                 const std::string& path,
                                                                 const char* key,
                                                                 const std::string& origin) {
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
  Channel c;
  c.signal = *s;
  c.id = m->id;
  c.bytes = s->bytes_spanned();
  if (s->mux_value >= 0) {
    const can::DbcSignal* mux = nullptr;
    for (const auto& ss : m->signals) {
      if (ss.multiplexor) mux = &ss;
    }
    if (!mux) {
      return Error(Errc::kInvalidArgument,
                   "can odometry: signal %s is multiplexed (m%d) but message %s in %s has no "
                   "multiplexor (M) signal",
                   path.c_str(), s->mux_value, msg.c_str(), origin.c_str());
    }
    c.muxed = true;
    c.mux = *mux;
    c.mux_bytes = mux->bytes_spanned();
    c.mux_value = uint64_t(s->mux_value);
  }
  return c;
}

Expected<CanOdometryDecoder> CanOdometryDecoder::create(const can::Dbc& dbc,
                                                        const CanOdometryOptions& o,
                                                        const std::string& origin) {
  auto speed = locate(dbc, o.speed, "speed", origin);
  if (!speed) return speed.error();
  auto yaw = locate(dbc, o.yaw_rate, "yaw_rate", origin);
  if (!yaw) return yaw.error();
  CanOdometryDecoder d;
  d.speed_ = speed.value();
  d.yaw_ = yaw.value();
  const std::string su = o.speed_unit.empty() ? d.speed_.signal.unit : o.speed_unit;
  const std::string yu = o.yaw_rate_unit.empty() ? d.yaw_.signal.unit : o.yaw_rate_unit;
  d.speed_.scale = speed_unit_scale(su);
  d.yaw_.scale = yaw_rate_unit_scale(yu);
  if (d.speed_.scale == 0) {
    return Error(Errc::kInvalidArgument,
                 "can odometry: %s's unit '%s' is not a speed aprt knows (m/s, km/h, mph); set "
                 "odometry.can.speed_unit to the unit its factor gives",
                 o.speed.c_str(), su.c_str());
  }
  if (d.yaw_.scale == 0) {
    return Error(Errc::kInvalidArgument,
                 "can odometry: %s's unit '%s' is not a yaw rate aprt knows (rad/s, deg/s); set "
                 "odometry.can.yaw_rate_unit to the unit its factor gives",
                 o.yaw_rate.c_str(), yu.c_str());
  }
  if (o.yaw_rate_clockwise) d.yaw_.scale = -d.yaw_.scale;
  if (o.max_pair_age_ms < 1) {
    return Error(Errc::kInvalidArgument, "can odometry: max_pair_age_ms %d must be >= 1",
                 o.max_pair_age_ms);
  }
  d.max_pair_age_ns_ = int64_t(o.max_pair_age_ms) * 1000000;
  d.description_ = o.speed + " [" + su + "] + " + o.yaw_rate + " [" + yu + "]" +
                   (o.yaw_rate_clockwise ? " (clockwise)" : "");
  if (!o.direction.empty()) {
    auto dir = locate(dbc, o.direction, "direction", origin);
    if (!dir) return dir.error();
    if (o.reverse_values.empty()) {
      // Say what the DBC calls each value, so the user can pick.
      std::string table;
      for (const auto& [raw, name] : dir.value().signal.values) {
        if (table.size() > 200) {
          table += ", ...";
          break;
        }
        table += (table.empty() ? "" : ", ") + std::to_string(raw) + " '" + name + "'";
      }
      return Error(
          Errc::kInvalidArgument,
          "can odometry: odometry.can.direction %s needs odometry.can.reverse_values "
          "(its raw values that mean reversing); %s",
          o.direction.c_str(),
          table.empty() ? "the DBC names none of its values" : ("the DBC names " + table).c_str());
    }
    d.direction_ = dir.value();
    d.has_direction_ = true;
    d.reverse_values_ = o.reverse_values;
    std::string rv;
    for (int v : o.reverse_values) rv += (rv.empty() ? "" : ", ") + std::to_string(v);
    d.description_ += ", direction " + o.direction + " (reverse: " + rv + ")";
  }
  return d;
}

int CanOdometryDecoder::ids(uint32_t out[3]) const {
  int n = 0;
  for (const Channel* c : {&speed_, &yaw_, &direction_}) {
    if (c == &direction_ && !has_direction_) break;
    bool seen = false;
    for (int i = 0; i < n; ++i) seen = seen || out[i] == c->id;
    if (!seen) out[n++] = c->id;
  }
  return n;
}

bool CanOdometryDecoder::carries(const Channel& c, const can::Frame& f) noexcept {
  if (f.id != c.id) return false;
  if (!c.muxed) return true;
  return f.len >= c.mux_bytes && c.mux.raw(f.data, f.len) == c.mux_value;
}

bool CanOdometryDecoder::decode(const Channel& c, const can::Frame& f, double* out) noexcept {
  if (f.len < c.bytes) {
    last_refusal_ = "frame shorter than its signal";
    return false;
  }
  const double v = c.signal.physical(f.data, f.len);
  // The DBC's own range (where one is given) excludes the ECU's invalid codes.
  if (c.signal.max > c.signal.min && (v < c.signal.min || v > c.signal.max)) {
    last_refusal_ = "value outside the DBC's range (an invalid code?)";
    return false;
  }
  *out = v * c.scale;
  return true;
}

bool CanOdometryDecoder::take_direction(const can::Frame& f, int64_t stamp_ns) noexcept {
  double unused;
  if (!decode(direction_, f, &unused)) {
    have_direction_ = false;
    return false;
  }
  // The raw value, as the DBC's value table and reverse_values count it.
  const int64_t raw = direction_.signal.integer(f.data, f.len);
  reversing_ = false;
  for (int v : reverse_values_) reversing_ = reversing_ || raw == v;
  direction_stamp_ns_ = stamp_ns;
  have_direction_ = true;
  return true;
}

CanOdometryDecoder::Result CanOdometryDecoder::on_frame(const can::Frame& f, int64_t stamp_ns,
                                                        TwistSample* out) noexcept {
  const bool is_yaw = carries(yaw_, f), is_speed = carries(speed_, f);
  const bool is_direction = has_direction_ && carries(direction_, f);
  if (!is_yaw && !is_speed && !is_direction) return Result::kIgnored;
  // A refused direction leaves none to pair with; the frame's yaw rate still counts.
  const bool direction_refused = is_direction && !take_direction(f, stamp_ns);
  if (is_yaw) {
    double w;
    if (!decode(yaw_, f, &w)) {
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
  }
  if (!is_speed) return direction_refused ? Result::kRefused : Result::kHeld;
  double v;
  if (!decode(speed_, f, &v)) return Result::kRefused;
  if (!(std::fabs(v) <= kMaxSpeedMps)) {
    last_refusal_ = "speed beyond 150 m/s";
    return Result::kRefused;
  }
  const int64_t age = stamp_ns - yaw_stamp_ns_;
  if (!have_yaw_ || age > max_pair_age_ns_ || age < -max_pair_age_ns_) {
    last_refusal_ = "no yaw rate within max_pair_age_ms of the speed";
    return Result::kRefused;
  }
  if (has_direction_) {
    const int64_t dage = stamp_ns - direction_stamp_ns_;
    if (!have_direction_ || dage > max_pair_age_ns_ || dage < -max_pair_age_ns_) {
      last_refusal_ = "no direction within max_pair_age_ms of the speed";
      return Result::kRefused;
    }
    v = reversing_ ? -std::fabs(v) : std::fabs(v);
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
  uint32_t ids[3];
  const int n = r->decoder_.ids(ids);
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
