// The pose on CAN, as config/aprt_pose.dbc defines it: classic CAN (five
// 8-byte frames per estimate) or CAN FD (one 48-byte frame), every frame
// protected AUTOSAR-E2E style -- CRC-8 SAE J1850 over a 16-bit data ID and
// the payload, a 4-bit alive counter shared by all frames of one estimate.
// Values outside a signal's range are saturated, flagged (bit 15) and the
// estimate marked not valid: nothing invalid goes out as valid.
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/can/can_frame.h"

namespace aprt::can {

struct PoseSignals {
  uint8_t state = 0;   // RunState
  uint16_t flags = 0;  // pose and loop flags (see the DBC comment)
  bool valid = false;
  double sigma_pos_m = 0, sigma_yaw_deg = 0;
  double x = 0, y = 0, z = 0;             // base_link in the map frame, metres
  double qw = 1, qx = 0, qy = 0, qz = 0;  // unit quaternion
  uint64_t timestamp_us = 0;              // source frame capture, since the Unix epoch
};

struct Ids {
  uint32_t status = 0x300, pos_xy = 0x301, pos_zqw = 0x302, quat_yz = 0x303, time = 0x304;
  uint32_t fd = 0x310;
};

inline constexpr uint16_t kFlagSaturated = 1u << 15;
inline constexpr int kClassicFrames = 5;
inline constexpr uint8_t kFdLength = 48;

// CRC-8 SAE J1850 (poly 0x1D, init 0xFF, xor-out 0xFF) over the data ID (low
// byte first) and payload[1..len) -- payload[0] is where the CRC goes.
uint8_t e2e_crc(uint16_t data_id, const uint8_t* payload, size_t len);

// @rt. `counter` 0..15. Returns the number of frames written.
int encode_classic(const PoseSignals& s, uint8_t counter, const Ids& ids,
                   Frame out[kClassicFrames]);
void encode_fd(const PoseSignals& s, uint8_t counter, const Ids& ids, Frame* out);

// Bits of a little-endian (Intel) signal.
void put_bits(uint8_t* data, int start, int length, uint64_t value);
uint64_t get_bits(const uint8_t* data, int start, int length);

// The receiving ECU's view: checks each frame's CRC and counter, assembles
// estimates (all five classic frames with one counter, or one FD frame).
class Decoder {
 public:
  enum class Event {
    kNone,
    kEstimate,
    kCrcError,
    kCounterRepeated,
    kCounterSkipped,
    kBadLength,
    kIncomplete,
    kUnknownId
  };
  explicit Decoder(const Ids& ids) : ids_(ids) {}
  // Feeds one frame; kEstimate fills *out. Other events are counted.
  Event feed(const Frame& f, PoseSignals* out);

  uint64_t crc_errors = 0, repeated = 0, skipped = 0, incomplete = 0, estimates = 0;

 private:
  int slot_of(uint32_t id) const;
  Ids ids_;
  int last_counter_[6] = {-1, -1, -1, -1, -1, -1};
  uint8_t group_counter_ = 0;
  uint8_t have_ = 0;  // bit per classic frame collected for group_counter_
  Frame group_[kClassicFrames];
};

const char* event_name(Decoder::Event e);

}  // namespace aprt::can
