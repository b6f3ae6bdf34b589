// The supervisor thread's duties around the state machine
// (runtime/loop/supervisor.h): each tick it steps the states from the
// stages' health, reports a change (stderr, systemd STATUS=), and pets the
// hardware watchdog and systemd's WATCHDOG=1 only while every stage beats --
// so a hung process resets the ECU. It records the run's state changes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "drivers/watchdog/watchdog_device.h"
#include "runtime/base/check.h"
#include "runtime/config/config.h"
#include "runtime/loop/loop_shared.h"
#include "runtime/loop/supervisor.h"

namespace aprt {

class Supervision {
 public:
  static constexpr size_t kMaxStateChanges = 64;

  // Opens the configured watchdog device (its failure is the run's).
  static Expected<std::unique_ptr<Supervision>> create(const Config& config);

  // systemd READY=1 (the threads run).
  void ready();
  // One tick: the new state, with notifications and pets. @rt.
  RunState tick(const Health& h, LoopShared& shared) noexcept;
  // systemd STOPPING=1; a clean stop (exit code 0) disarms the watchdog.
  void stopping(bool clean);

  const StateChange* state_changes(size_t* count) const {
    *count = count_;
    return changes_;
  }

 private:
  explicit Supervision(const Config& config)
      : cfg_(config.supervisor), sm_(config.supervisor), console_(config.output.console) {}
  Config::Supervisor cfg_;
  Supervisor sm_;
  bool console_;  // state lines go through the publish thread, in order with the poses
  std::unique_ptr<WatchdogDevice> watchdog_;
  RunState last_ = RunState::kStarting;
  StateChange changes_[kMaxStateChanges] = {};
  size_t count_ = 0;
};

// Makes a broken invariant (APRT_ENFORCE, runtime/base/check.h) in any of the
// loop's threads a FAULT: the reason on stderr and to systemd, then the
// process ends with FAULT's exit code 3 at once -- without the watchdog's
// magic close, so a supervised ECU resets. Returns the previous handler.
FatalHandler install_fault_handler(bool systemd) noexcept;
inline constexpr int kFaultExitCode = 3;

// systemd's notification protocol (sd_notify(3)): one datagram to
// $NOTIFY_SOCKET; nothing when it is not set.
void sd_notify_text(const char* text) noexcept;

}  // namespace aprt
