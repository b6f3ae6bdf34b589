// One CAN frame as aprt's CAN endpoints see it (classic or FD), shared by the
// pose sender (drivers/output/can) and the odometry reader
// (drivers/input/can_odometry).
#pragma once

#include <cstdint>

namespace aprt::can {

struct Frame {
  uint32_t id = 0;  // 11 or 29 bits (an id above 0x7FF goes out extended)
  uint8_t len = 0;
  bool fd = false;
  uint8_t data[64] = {};
};

}  // namespace aprt::can
