// The model the loop runs, and its replacement on SIGHUP. A loader thread of
// normal priority reads and checks the configured file into a second engine
// (signature, file, fit with the running pipeline) -- never the supervisor,
// whose watchdog pets must not wait for a disk, a large file or a FIFO at
// the model path. The supervisor starts a load, and takes its result at a
// later tick; the inference thread switches to the new engine between two
// frames and hands the old one back; the supervisor frees it (never the
// inference thread). A bad file leaves the running model in place, with the
// reason on stderr.
#pragma once

#include <pthread.h>
#include <semaphore.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "runtime/base/expected.h"
#include "runtime/config/config.h"
#include "runtime/engine/engine.h"

namespace aprt {

class ModelSlot {
 public:
  ModelSlot(const Config& config, std::unique_ptr<Engine> first);
  ~ModelSlot();
  ModelSlot(const ModelSlot&) = delete;
  ModelSlot& operator=(const ModelSlot&) = delete;

  // Starts the loader thread (normal scheduling): reloads need it.
  Status start_loader();
  // Stops it by `deadline_ns` (monotonic); false when it is still stuck in
  // a read then (the caller ends the process without it).
  bool stop_loader(int64_t deadline_ns);

  // The model now running, as the supervisor side sees it.
  const Engine& running() const { return *engine_; }
  Engine* first() const { return engine_.get(); }

  // Async-signal-safe.
  void request_reload() { reload_requested_.store(true, std::memory_order_release); }
  // Supervisor thread, each tick, never blocking: completes a switch the
  // inference thread made, takes a finished load, starts a requested one.
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
  // True while a load is under way (tests wait for it to finish).
  bool loading() const { return phase_.load(std::memory_order_acquire) != kIdle; }

 private:
  enum Phase : int { kIdle, kLoading, kLoaded };
  static void* loader_main(void* self);
  void load();

  const Config& config_;
  std::unique_ptr<Engine> engine_;  // the model inference runs (owned by the supervisor side)
  std::unique_ptr<Engine> spare_;   // a reloaded model, until inference has switched to it
  std::atomic<Engine*> pending_{nullptr};  // supervisor -> inference: switch to this
  std::atomic<Engine*> retired_{nullptr};  // inference -> supervisor: no longer used
  std::atomic<bool> reload_requested_{false};
  uint64_t reloads_ = 0, refused_ = 0;

  // supervisor -> loader: sem_post after setting kLoading; loader ->
  // supervisor: loaded_/message_ written, then kLoaded (release).
  std::atomic<int> phase_{kIdle};
  std::atomic<bool> stop_{false};
  sem_t wake_;
  pthread_t loader_{};
  bool loader_started_ = false;
  std::unique_ptr<Engine> loaded_;  // the load's result (null: refused, see message_)
  std::string message_;             // the refusal, or the signature note
};

}  // namespace aprt
