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
// max_pair_age_ms old. A vehicle whose speed signal has no sign (most
// wheel-speed signals) names its direction of travel (a gear or direction
// signal, in any of the messages or a third) and the raw values that mean
// reverse: the speed then takes the sign of the latest direction at most
// max_pair_age_ms old. A multiplexed signal (m<k>) is read from the frames
// whose multiplexor is k; the others do not carry it and are passed over.
// Values come in the DBC's units (m/s, km/h, mph; rad/s, deg/s), converted
// to SI; a value outside the signal's DBC range (where ECUs put their
// "invalid" codes) or beyond physical bounds is refused and counted, never
// used.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

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
  int max_pair_age_ms = 100;        // the yaw rate's (direction's) age a speed may pair with
  std::string direction;            // "MESSAGE.SIGNAL" of the direction of travel ("": the
                                    // speed is signed)
  std::vector<int> reverse_values;  // the direction's raw values that mean reversing
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

  uint32_t speed_id() const { return speed_.id; }
  uint32_t yaw_rate_id() const { return yaw_.id; }
  // The distinct ids the decoder reads (the kernel filter): 1 to 3.
  int ids(uint32_t out[3]) const;
  // "ESP_21.VEHICLE_SPEED [km/h] + ESP_21.YAW_RATE [deg/s]" for messages.
  const std::string& description() const { return description_; }
  // Why the last kRefused (a static string).
  const char* last_refusal() const { return last_refusal_; }

 private:
  // One signal located in the DBC: its message's id, the bytes a frame
  // needs, and, for a multiplexed signal, the multiplexor and its value.
  struct Channel {
    can::DbcSignal signal;
    uint32_t id = 0;
    int bytes = 0;
    double scale = 1;
    bool muxed = false;
    can::DbcSignal mux;
    int mux_bytes = 0;
    uint64_t mux_value = 0;
  };
  static Expected<Channel> locate(const can::Dbc& dbc, const std::string& path, const char* key,
                                  const std::string& origin);

  CanOdometryDecoder() = default;
  // Whether this frame carries the channel's signal (its id; its
  // multiplexor's value).
  static bool carries(const Channel& c, const can::Frame& f) noexcept;
  bool decode(const Channel& c, const can::Frame& f, double* out) noexcept;
  // Takes the direction a frame carries (reversing or not); false: refused.
  bool take_direction(const can::Frame& f, int64_t stamp_ns) noexcept;

  Channel speed_, yaw_, direction_;
  bool has_direction_ = false;
  std::vector<int> reverse_values_;
  int64_t max_pair_age_ns_ = 0;
  double yaw_value_ = 0;
  int64_t yaw_stamp_ns_ = 0;
  bool have_yaw_ = false;
  bool reversing_ = false;
  int64_t direction_stamp_ns_ = 0;
  bool have_direction_ = false;
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
