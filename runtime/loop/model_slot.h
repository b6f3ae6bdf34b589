// The model the loop runs, and its replacement on SIGHUP: the supervisor
// thread loads and checks the configured file into a second engine
// (signature, file, fit with the running pipeline); the inference thread
// switches to it between two frames and hands the old one back; the
// supervisor frees it (never the inference thread). A bad file leaves the
// running model in place, with the reason on stderr.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>

#include "runtime/config/config.h"
#include "runtime/engine/engine.h"

namespace aprt {

class ModelSlot {
 public:
  ModelSlot(const Config& config, std::unique_ptr<Engine> first)
      : config_(config), engine_(std::move(first)) {}

  // The model now running, as the supervisor side sees it.
  const Engine& running() const { return *engine_; }
  Engine* first() const { return engine_.get(); }

  // Async-signal-safe.
  void request_reload() { reload_requested_.store(true, std::memory_order_release); }
  // Supervisor thread: completes a switch the inference thread made; starts
  // a requested reload.
  void service();
  // Inference thread, between two frames: the model to switch to, or null.
  // The caller hands back the one it ran with retire().
  Engine* take_pending() noexcept { return pending_.exchange(nullptr, std::memory_order_acq_rel); }
  void retire(Engine* old) noexcept { retired_.store(old, std::memory_order_release); }
  // After the threads ended: a switch made after the last service, and a
  // reload the inference thread never reached.
  void finish();

  uint64_t reloads() const { return reloads_; }
  uint64_t refused() const { return refused_; }

 private:
  const Config& config_;
  std::unique_ptr<Engine> engine_;  // the model inference runs (owned by the supervisor side)
  std::unique_ptr<Engine> spare_;   // a reloaded model, until inference has switched to it
  std::atomic<Engine*> pending_{nullptr};  // supervisor -> inference: switch to this
  std::atomic<Engine*> retired_{nullptr};  // inference -> supervisor: no longer used
  std::atomic<bool> reload_requested_{false};
  uint64_t reloads_ = 0, refused_ = 0;
};

}  // namespace aprt
