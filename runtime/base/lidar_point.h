// One LiDAR point as drivers deliver it and the LiDAR kernels read it
// (DESIGN.md 4.2 / 4.3; docs/lidar.md).
#pragma once

namespace aprt {

struct LidarPoint {
  float x, y, z, intensity;  // sensor frame, metres; x forward, y left, z up
};

}  // namespace aprt
