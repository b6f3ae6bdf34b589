#include "runtime/loop/fault_injector.h"

#include <poll.h>
#include <unistd.h>

#include <climits>

namespace aprt {

void FaultInjector::block(int64_t ns) noexcept {
  int fds[2];
  if (pipe(fds) != 0) return;
  pollfd p{fds[0], POLLIN, 0};
  const int64_t ms = ns / 1000000;
  // One call; a signal (EINTR) ends it early, as it would a real stuck read.
  (void)poll(&p, 1, ms > INT_MAX ? INT_MAX : int(ms));
  close(fds[0]);
  close(fds[1]);
}

Status FaultInjector::configure(const std::vector<FaultSpec>& faults) {
  if (faults.size() > size_t(kMaxFaults)) {
    return Error(Errc::kInvalidArgument, "fault_injection: at most %d faults, got %zu", kMaxFaults,
                 faults.size());
  }
  n_ = 0;
  for (const FaultSpec& f : faults) faults_[n_++] = f;
  return ok();
}

int64_t FaultInjector::once(FaultKind k, uint64_t i) const noexcept {
  int64_t ns = 0;
  for (int j = 0; j < n_; ++j) {
    if (faults_[j].kind == k && faults_[j].at_frame == i)
      ns += int64_t(faults_[j].duration_ms * 1e6);
  }
  return ns;
}

int64_t FaultInjector::window_ns(FaultKind k, uint64_t i) const noexcept {
  int64_t ns = 0;
  for (int j = 0; j < n_; ++j) {
    const FaultSpec& f = faults_[j];
    if (f.kind == k && i >= f.at_frame && i < f.at_frame + f.count)
      ns += int64_t(f.duration_ms * 1e6);
  }
  return ns;
}

bool FaultInjector::in_window(FaultKind k, uint64_t i) const noexcept {
  for (int j = 0; j < n_; ++j) {
    const FaultSpec& f = faults_[j];
    if (f.kind == k && i >= f.at_frame && i < f.at_frame + f.count) return true;
  }
  return false;
}

}  // namespace aprt
