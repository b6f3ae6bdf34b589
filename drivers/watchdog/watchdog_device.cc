#include "drivers/watchdog/watchdog_device.h"

#include <fcntl.h>
#include <linux/watchdog.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <new>

namespace aprt {

Expected<std::unique_ptr<WatchdogDevice>> WatchdogDevice::open(const std::string& path,
                                                               int timeout_s,
                                                               std::string* warning) {
  std::unique_ptr<WatchdogDevice> w(new (std::nothrow) WatchdogDevice());
  if (!w) return Error(Errc::kOutOfMemory, "run: out of memory");
  w->fd_ = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (w->fd_ < 0) {
    return Error(Errc::kIo, "run: cannot open watchdog %s: %s", path.c_str(), std::strerror(errno));
  }
  int timeout = timeout_s;
  if (ioctl(w->fd_, WDIOC_SETTIMEOUT, &timeout) != 0 && warning) {
    *warning = "warning: watchdog refused a " + std::to_string(timeout_s) + " s timeout (" +
               std::strerror(errno) + "); using its own";
  }
  return w;
}

WatchdogDevice::~WatchdogDevice() {
  if (fd_ >= 0) close(fd_);
}

void WatchdogDevice::pet() noexcept {
  ioctl(fd_, WDIOC_KEEPALIVE, 0);
}

bool WatchdogDevice::magic_close() noexcept {
  return write(fd_, "V", 1) == 1;
}

}  // namespace aprt
