// Finding V4L2 capture devices by what they are rather than by node number:
// /dev/videoN numbers follow probe order and change when a camera is
// re-plugged; a card name ("HD Pro Webcam C920") or a bus position
// ("usb-0000:00:14.0-2") does not. Used on every (re)open, so a camera that
// comes back under another node is found again. No allocation.
#pragma once

#include <cstddef>
#include <cstdint>

#include "runtime/base/expected.h"

namespace aprt {

struct V4l2DeviceInfo {
  char path[24];
  char card[32];
  char bus_info[32];
  char driver[16];
  uint32_t caps;  // device capabilities
};

// The streaming video capture nodes /dev/video0..63, in number order; returns
// how many (at most `max` written).
int list_v4l2_capture_devices(V4l2DeviceInfo* out, int max);

// `name`: a path (starts with '/'), used as it is; otherwise the first capture
// node whose card name or bus_info equals it. The path goes to `path`.
Status resolve_v4l2_device(const char* name, char* path, size_t path_size);

}  // namespace aprt
