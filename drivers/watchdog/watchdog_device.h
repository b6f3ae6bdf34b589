// A hardware (or softdog) watchdog, /dev/watchdog (linux/watchdog.h): opened
// with a timeout, petted while the supervisor says every stage is alive,
// closed with the magic character on a clean stop so that stopping aprt does
// not reset the ECU. A hung process stops petting it and the watchdog resets
// the machine.
#pragma once

#include <memory>
#include <string>

#include "runtime/base/expected.h"

namespace aprt {

class WatchdogDevice {
 public:
  // `warning` receives a line when the device refused the timeout (it keeps its own).
  static Expected<std::unique_ptr<WatchdogDevice>> open(const std::string& path, int timeout_s,
                                                        std::string* warning);
  ~WatchdogDevice();
  WatchdogDevice(const WatchdogDevice&) = delete;
  WatchdogDevice& operator=(const WatchdogDevice&) = delete;

  // @rt: one ioctl.
  void pet() noexcept;
  // Disarms a watchdog that supports WDIOF_MAGICCLOSE; false if the write failed.
  bool magic_close() noexcept;

 private:
  WatchdogDevice() = default;
  int fd_ = -1;
};

}  // namespace aprt
