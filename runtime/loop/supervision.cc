#include "runtime/loop/supervision.h"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <string>

namespace aprt {

void sd_notify_text(const char* text) noexcept {
  const char* path = std::getenv("NOTIFY_SOCKET");
  if (!path || !*path) return;
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  const size_t n = std::strlen(path);
  if (n >= sizeof addr.sun_path) return;
  std::memcpy(addr.sun_path, path, n);
  if (addr.sun_path[0] == '@') addr.sun_path[0] = '\0';  // abstract namespace
  const int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return;
  sendto(fd, text, std::strlen(text), MSG_NOSIGNAL, reinterpret_cast<sockaddr*>(&addr),
         socklen_t(offsetof(sockaddr_un, sun_path) + n));
  close(fd);
}

namespace {

std::atomic<bool> g_fault_systemd{false};

void fault_handler(const char* file, int line, const char* message) {
  // Async-signal-safe enough for a dying process: fixed buffers, write(2), _exit(2).
  char text[320];
  const int n = std::snprintf(text, sizeof text, "aprt run: state FAULT (fatal: %s at %s:%d)\n",
                              message, file, line);
  if (n > 0) (void)!write(STDERR_FILENO, text, size_t(std::min(n, int(sizeof text) - 1)));
  if (g_fault_systemd.load()) {
    std::snprintf(text, sizeof text, "STATUS=FAULT: fatal: %s", message);
    sd_notify_text(text);
  }
  _exit(kFaultExitCode);
}

}  // namespace

FatalHandler install_fault_handler(bool systemd) noexcept {
  g_fault_systemd.store(systemd);
  return set_fatal_handler(&fault_handler);
}

Expected<std::unique_ptr<Supervision>> Supervision::create(const Config& config) {
  std::unique_ptr<Supervision> s(new (std::nothrow) Supervision(config));
  if (!s) return Error(Errc::kOutOfMemory, "run: out of memory");
  if (!config.supervisor.watchdog_device.empty()) {
    std::string warning;
    auto wd = WatchdogDevice::open(config.supervisor.watchdog_device,
                                   config.supervisor.watchdog_timeout_s, &warning);
    if (!wd) return wd.error();
    if (!warning.empty()) std::fprintf(stderr, "aprt run: %s\n", warning.c_str());
    s->watchdog_ = std::move(wd.value());
  }
  return s;
}

void Supervision::ready() {
  if (cfg_.systemd) sd_notify_text("READY=1\nSTATUS=STARTING");
}

RunState Supervision::tick(const Health& h, LoopShared& shared) noexcept {
  const RunState st = sm_.step(h);
  shared.state.store(uint8_t(st), std::memory_order_relaxed);
  shared.reason.store(sm_.reason(), std::memory_order_release);
  if (st != last_) {
    if (count_ < kMaxStateChanges) changes_[count_++] = {st, sm_.reason(), h.now_ns};
    char msg[192];
    std::snprintf(msg, sizeof msg, "STATUS=%s: %s", run_state_name(st), sm_.reason());
    if (cfg_.systemd) sd_notify_text(msg);
    if (st != RunState::kRunning || last_ != RunState::kStarting) {
      if (!console_ || !shared.state_lines.push({st, sm_.reason(), h.now_ns})) {
        std::fprintf(stderr, "aprt run: state %s (%s)\n", run_state_name(st), sm_.reason());
      }
    }
    last_ = st;
  }
  if (st != RunState::kFault && sm_.stages_alive()) {
    if (watchdog_) watchdog_->pet();
    if (cfg_.systemd) sd_notify_text("WATCHDOG=1");
  }
  return st;
}

void Supervision::stopping(bool clean) {
  if (cfg_.systemd) sd_notify_text("STOPPING=1");
  if (watchdog_ && clean && !watchdog_->magic_close()) {
    // magic close: a clean stop does not reset the ECU
    std::fprintf(stderr, "aprt run: warning: watchdog magic close failed\n");
  }
}

}  // namespace aprt
