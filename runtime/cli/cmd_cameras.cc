// aprt cameras: the cameras this machine offers, as the configuration names
// them -- V4L2 capture nodes with card name, bus_info and pixel formats
// (source.v4l2.device takes any of path, card name or bus_info), and the
// cameras libcamera sees (source.libcamera.camera takes the id or index).
#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>

#include "drivers/input/camera/libcamera_source.h"
#include "drivers/input/camera/v4l2_devices.h"
#include "runtime/cli/args.h"
#include "runtime/cli/commands.h"

namespace aprt::cli {

int cmd_cameras(int argc, char** argv) {
  Args args(argc, argv);
  if (args.flag("--help")) {
    std::printf(
        "usage: aprt cameras\n"
        "  lists V4L2 capture devices (path, card name, bus_info, driver, formats) and\n"
        "  libcamera cameras (index: id), for source.v4l2.device / source.libcamera.camera\n");
    return 0;
  }
  if (args.refuse("cameras")) return 2;
  V4l2DeviceInfo devs[64];
  const int n = list_v4l2_capture_devices(devs, 64);
  std::printf("V4L2 capture devices: %d\n", n);
  for (int i = 0; i < n && i < 64; ++i) {
    const V4l2DeviceInfo& d = devs[i];
    char formats[128] = "";
    const int fd = open(d.path, O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd >= 0) {
      v4l2_fmtdesc f{};
      f.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      for (f.index = 0; f.index < 16 && ioctl(fd, VIDIOC_ENUM_FMT, &f) == 0; ++f.index) {
        char t[6] = {char(f.pixelformat),
                     char(f.pixelformat >> 8),
                     char(f.pixelformat >> 16),
                     char(f.pixelformat >> 24),
                     ' ',
                     '\0'};
        std::strncat(formats, t, sizeof formats - std::strlen(formats) - 1);
      }
      close(fd);
    }
    std::printf("  %-12s card '%s'  bus_info '%s'  driver %s  formats %s\n", d.path, d.card,
                d.bus_info, d.driver, formats[0] ? formats : "(none listed)");
  }
  std::printf("libcamera cameras: %s\n", LibcameraSource::list_cameras().c_str());
  return 0;
}

}  // namespace aprt::cli
