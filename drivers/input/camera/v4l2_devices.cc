#include "drivers/input/camera/v4l2_devices.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace aprt {
namespace {

void copy_text(char* dst, size_t n, const uint8_t* src, size_t src_n) {
  size_t i = 0;
  for (; i + 1 < n && i < src_n && src[i]; ++i) dst[i] = char(src[i]);
  dst[i] = '\0';
}

}  // namespace

int list_v4l2_capture_devices(V4l2DeviceInfo* out, int max) {
  int found = 0;
  for (int i = 0; i < 64; ++i) {
    char path[24];
    std::snprintf(path, sizeof path, "/dev/video%d", i);
    const int fd = open(path, O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) continue;
    v4l2_capability cap{};
    const bool ok = ioctl(fd, VIDIOC_QUERYCAP, &cap) == 0;
    close(fd);
    if (!ok) continue;
    const uint32_t caps =
        (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
    if (!(caps & V4L2_CAP_VIDEO_CAPTURE) || !(caps & V4L2_CAP_STREAMING)) continue;
    if (found < max) {
      V4l2DeviceInfo& d = out[found];
      std::snprintf(d.path, sizeof d.path, "%s", path);
      copy_text(d.card, sizeof d.card, cap.card, sizeof cap.card);
      copy_text(d.bus_info, sizeof d.bus_info, cap.bus_info, sizeof cap.bus_info);
      copy_text(d.driver, sizeof d.driver, cap.driver, sizeof cap.driver);
      d.caps = caps;
    }
    ++found;
  }
  return found;
}

Status resolve_v4l2_device(const char* name, char* path, size_t path_size) {
  if (name[0] == '/') {
    std::snprintf(path, path_size, "%s", name);
    return ok();
  }
  V4l2DeviceInfo devs[16];
  const int n = list_v4l2_capture_devices(devs, 16);
  char seen[160] = "";
  for (int i = 0; i < n && i < 16; ++i) {
    if (std::strcmp(devs[i].card, name) == 0 || std::strcmp(devs[i].bus_info, name) == 0) {
      std::snprintf(path, path_size, "%s", devs[i].path);
      return ok();
    }
    char one[112];
    std::snprintf(one, sizeof one, "%s%.23s '%.31s' %.31s", seen[0] ? ", " : "", devs[i].path,
                  devs[i].card, devs[i].bus_info);
    std::strncat(seen, one, sizeof seen - std::strlen(seen) - 1);
  }
  return Error(Errc::kNotFound,
               "v4l2: no capture device with card name or bus_info '%s' (found: %s; `aprt "
               "cameras` lists them)",
               name, seen[0] ? seen : "none");
}

}  // namespace aprt
