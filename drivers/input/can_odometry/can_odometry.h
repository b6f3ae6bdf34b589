// The vehicle's motion from its own CAN bus (odometry.source: can): the
// speed and yaw-rate signals its ECUs already broadcast (ABS/ESP wheel speed,
// the yaw-rate sensor), located by the vehicle's DBC file, become the
// TwistSamples the pose filter integrates (drivers/input/twist/twist_reader.h)
// -- the same as a ROS 2 twist topic gives, for a vehicle without ROS.
//
// Two parts:
//   CanOdometryDecoder  frames in, samples out: pure, allocation-free per
//                       frame, tested without a bus;
//   CanTwistReader      a SocketCAN reader (drivers/can/socketcan.h, kernel
//                       filter on the two ids, kernel receive stamps) around
//                       it, reopening an interface that vanished or is not
//                       there yet.
// A sample is stamped with the frame's kernel receive time (CLOCK_REALTIME,
// the clock live frames are put on, runtime/loop/estimator.cc). Speed and
// yaw rate in one message give one sample per message; in two messages, one
// sample per speed message with the latest yaw rate, when that is at most
// max_pair_age_ms old. Values come in the DBC's units (m/s, km/h, mph;
// rad/s, deg/s), converted to SI; a value outside the signal's DBC range
// (where ECUs put their "invalid" codes) or beyond physical bounds is refused
// and counted, never used.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "drivers/can/can_frame.h"
#include "drivers/can/dbc.h"
#include "drivers/can/socketcan.h"
#include "drivers/input/twist/twist_reader.h"
#include "runtime/base/expected.h"

namespace aprt {

struct CanOdometryOptions {
  std::string interface = "can0";
  std::string dbc;                  // the vehicle's DBC file
  std::string speed;                // "MESSAGE.SIGNAL": speed along the vehicle's heading
  std::string yaw_rate;             // "MESSAGE.SIGNAL"
  std::string speed_unit;           // "" : the DBC's; else m/s, km/h or mph
  std::string yaw_rate_unit;        // "" : the DBC's; else rad/s or deg/s
  bool yaw_rate_clockwise = false;  // the signal counts clockwise positive (ROS: counter-clockwise)
  int max_pair_age_ms = 100;        // two messages: the yaw rate's age a speed may pair with
};

// SI per unit of a DBC unit string (m/s, km/h, kph, kmh, mph; rad/s, deg/s,
// °/s); 0 for a unit of the other quantity or none known.
double speed_unit_scale(const std::string& unit);
double yaw_rate_unit_scale(const std::string& unit);

class CanOdometryDecoder {
 public:
  // Finds the two signals in `dbc`; errors name the file's messages or the
  // message's signals when one is not there.
  static Expected<CanOdometryDecoder> create(const can::Dbc& dbc, const CanOdometryOptions& o,
                                             const std::string& origin);

  enum class Result : uint8_t {
    kIgnored,  // another id (a bus without a kernel filter)
    kSample,   // *out holds a sample
    kHeld,     // a yaw rate kept for the next speed
    kRefused,  // short frame, out of range, or a speed without a recent yaw rate
  };
  // One frame received at stamp_ns (CLOCK_REALTIME). @rt.
  Result on_frame(const can::Frame& f, int64_t stamp_ns, TwistSample* out) noexcept;

  uint32_t speed_id() const { return speed_id_; }
  uint32_t yaw_rate_id() const { return yaw_id_; }
  // "ESP_21.VEHICLE_SPEED [km/h] + ESP_21.YAW_RATE [deg/s]" for messages.
  const std::string& description() const { return description_; }
  // Why the last kRefused (a static string).
  const char* last_refusal() const { return last_refusal_; }

 private:
  CanOdometryDecoder() = default;
  bool decode(const can::DbcSignal& s, int bytes, const can::Frame& f, double scale,
              double* out) noexcept;

  can::DbcSignal speed_, yaw_;
  uint32_t speed_id_ = 0, yaw_id_ = 0;
  int speed_bytes_ = 0, yaw_bytes_ = 0;  // bytes a frame must have to carry the signal
  double speed_scale_ = 1, yaw_scale_ = 1;
  int64_t max_pair_age_ns_ = 0;
  double yaw_value_ = 0;
  int64_t yaw_stamp_ns_ = 0;
  bool have_yaw_ = false;
  std::string description_;
  const char* last_refusal_ = "";
};

class CanTwistReader final : public TwistReader {
 public:
  // Reads the DBC and opens the interface; an interface that does not exist
  // yet is not an error (it is tried again every second, as a CAN
  // controller may come up after aprt), a kernel without SocketCAN is.
  static Expected<std::unique_ptr<CanTwistReader>> create(const CanOdometryOptions& o);
  ~CanTwistReader() override = default;

  int take(TwistSample* out, int max, int64_t timeout_ns) override;
  // 1 while frames of the two ids arrive (one within the last second), else 0.
  int publishers() const override;
  const std::string& description() const { return decoder_.description(); }
  // Times the interface was bound again after it vanished or went down.
  uint64_t reopened() const { return reopened_; }

 private:
  CanTwistReader(CanOdometryDecoder d) : decoder_(std::move(d)) {}
  void try_reopen(int64_t now_ns) noexcept;

  CanOdometryDecoder decoder_;
  std::unique_ptr<can::SocketCan> socket_;
  bool bound_ = false;
  int64_t next_reopen_ns_ = 0;
  std::atomic<int64_t> last_frame_ns_{0};  // monotonic; read by publishers() from any thread
  uint64_t reopened_ = 0;
};

}  // namespace aprt
