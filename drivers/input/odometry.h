// The vehicle's own motion between two instants, from its speed and yaw rate
// (wheel odometry and a gyro, as every vehicle bus carries them).
//
// An absolute pose regressor's errors are large now and then and correlated
// over a few frames; the vehicle's motion between frames is known to a few
// per cent. The pose filter (runtime/pose/pose_filter.h) carries its pose
// from frame to frame with this motion and weighs each estimate against it.
//
// A series is a time-ordered list of samples, each holding from its stamp
// until the next (zero-order hold, as a bus message holds until the next
// one). Replays read it from a drive's odometry.txt ("seconds speed_mps
// yaw_rate_radps" per line, on the drive's recording clock: its times.txt,
// or frame index / 25 Hz without one; `python3 -m aprt_tools odometry DRIVE`
// writes one). Built at start-up; motion() allocates nothing.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "runtime/base/expected.h"

namespace aprt {

struct OdometrySample {
  double t_s = 0;             // on the frames' clock
  double speed_mps = 0;       // along the vehicle's heading (negative: reversing)
  double yaw_rate_radps = 0;  // counter-clockwise seen from above
};

// The planar motion of base_link from t0 to t1, in base_link's frame at t0.
struct PlanarMotion {
  double dx = 0, dy = 0, dyaw = 0;  // m, m, rad
  double distance_m = 0;            // path length (for the noise the filter adds)
  double dt_s = 0;
};

// The vehicle's pose in the odometry frame (where a continuous stretch of
// odometry began), integrated up to a frame's time: what a frame carries, so
// the motion between any two frames follows from their readings however
// many frames lay between them (a consumer that drops frames loses nothing).
// A new epoch begins where the odometry broke off (a gap, a replay that
// loops): readings of two epochs give no motion.
struct OdometryReading {
  bool valid = false;
  uint32_t epoch = 0;
  double x = 0, y = 0, yaw = 0;  // m, m, rad in the odometry frame
  double distance_m = 0;         // travelled since the epoch began
  double t_s = 0;
};

// base_link's motion from reading a to reading b (b later); false unless
// both are valid and of one epoch. @rt.
bool motion_between(const OdometryReading& a, const OdometryReading& b, PlanarMotion* out) noexcept;

class OdometrySeries {
 public:
  // The samples must be in strictly increasing time.
  static Expected<OdometrySeries> from_samples(std::vector<OdometrySample> samples,
                                               const char* what);
  // odometry.txt: '#' comments, then "seconds speed_mps yaw_rate_radps" per
  // line. Errors name the file and line.
  static Expected<OdometrySeries> parse(std::string_view text, const char* path);
  static Expected<OdometrySeries> load(const char* path);

  // The motion from t0 to t1 (t0 <= t1); false when the series does not
  // cover [t0, t1]: before its first sample, or more than `max_gap_s` past a
  // sample (a bus that went silent says nothing of the motion after). @rt.
  bool motion(double t0, double t1, PlanarMotion* out) const noexcept;

  size_t size() const { return samples_.size(); }
  // The longest a sample is held before the series counts as silent.
  static constexpr double kMaxGapS = 0.5;

 private:
  std::vector<OdometrySample> samples_;
};

// A live odometry's recent past, integrated: samples in (in time order, on
// one clock), the reading at any time within it out -- between two samples
// the earlier one holds, after the newest it holds for at most
// OdometrySeries::kMaxGapS. A gap longer than that, or a stamp that goes
// back, begins a new epoch. Fixed capacity, owned by one thread (the
// inference thread, fed from the odometry thread's queue). @rt: no
// allocation.
class OdometryTrack {
 public:
  static constexpr int kCapacity = 1024;  // ~10 s of a 100 Hz bus

  void add(const OdometrySample& s) noexcept;
  OdometryReading at(double t_s) const noexcept;

 private:
  struct Entry {
    OdometrySample s;
    OdometryReading r;  // the reading at s.t_s
  };
  Entry e_[kCapacity];
  int head_ = 0, size_ = 0;  // ring: head_ is the next slot
  uint32_t epoch_ = 0;
};

}  // namespace aprt
