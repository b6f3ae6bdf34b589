#include "runtime/loop/model_slot.h"

#include <time.h>

#include <cstdio>
#include <string>

#include "runtime/loop/model_loader.h"
#include "runtime/loop/rt_thread.h"

namespace aprt {

ModelSlot::ModelSlot(const Config& config, std::unique_ptr<Engine> first)
    : config_(config), engine_(std::move(first)) {
  sem_init(&wake_, 0, 0);
}

ModelSlot::~ModelSlot() {
  // Runtime stops the loader with a bound first; here only an idle one is left.
  if (loader_started_ && stop_loader(0)) loader_started_ = false;
  if (!loader_started_) sem_destroy(&wake_);
}

Status ModelSlot::start_loader() {
  if (loader_started_) return ok();
  if (Status s = start_thread(&loader_, loader_main, this, ThreadConfig{}, "aprt-reload"); !s) {
    return s;
  }
  loader_started_ = true;
  return ok();
}

bool ModelSlot::stop_loader(int64_t deadline_ns) {
  if (!loader_started_) return true;
  stop_.store(true, std::memory_order_release);
  sem_post(&wake_);
  if (!join_thread_by(loader_, deadline_ns)) return false;
  loader_started_ = false;
  return true;
}

void* ModelSlot::loader_main(void* self) {
  ModelSlot& m = *static_cast<ModelSlot*>(self);
  while (!m.stop_.load(std::memory_order_acquire)) {
    // Woken by a request or by stop; the timeout only re-checks stop.
    timespec t{};
    clock_gettime(CLOCK_MONOTONIC, &t);
    t.tv_sec += 1;
    if (sem_clockwait(&m.wake_, CLOCK_MONOTONIC, &t) != 0) continue;
    if (m.phase_.load(std::memory_order_acquire) == kLoading) m.load();
  }
  return nullptr;
}

void ModelSlot::load() {
  std::string note;
  auto next = load_model(model_request(config_), &note);
  Status fits = next ? reload_compatible(engine_->meta(), next.value()->meta()) : ok();
  if (next && fits) {
    loaded_ = std::move(next.value());
    message_ = note;
  } else {
    loaded_.reset();
    message_ = next ? fits.error().message() : next.error().message();
  }
  phase_.store(kLoaded, std::memory_order_release);
}

void ModelSlot::service() {
  if (retired_.exchange(nullptr, std::memory_order_acq_rel)) {
    engine_.swap(spare_);  // engine_: the model now running; spare_: the old one
    spare_.reset();
    ++reloads_;
    std::fprintf(stderr, "aprt run: model reloaded: %s (%s kernels); reload %llu\n",
                 config_.model.c_str(), engine_->isa(), static_cast<unsigned long long>(reloads_));
  }
  if (phase_.load(std::memory_order_acquire) == kLoaded) {
    if (!loaded_) {
      ++refused_;
      std::fprintf(stderr, "aprt run: reload refused, the running model stays: %s\n",
                   message_.c_str());
    } else {
      if (!message_.empty())
        std::fprintf(stderr, "aprt run: %s: %s\n", config_.model.c_str(), message_.c_str());
      spare_ = std::move(loaded_);
      pending_.store(spare_.get(), std::memory_order_release);
    }
    phase_.store(kIdle, std::memory_order_release);
  }
  if (!reload_requested_.exchange(false, std::memory_order_acq_rel)) return;
  if (spare_ || phase_.load(std::memory_order_acquire) != kIdle) {
    std::fprintf(stderr, "aprt run: reload requested while one is under way; ignored\n");
    return;
  }
  if (!loader_started_) {
    std::fprintf(stderr, "aprt run: reload requested but no loader thread runs; ignored\n");
    return;
  }
  phase_.store(kLoading, std::memory_order_release);
  sem_post(&wake_);
}

void ModelSlot::finish() {
  service();
  if (pending_.exchange(nullptr)) spare_.reset();
}

}  // namespace aprt
