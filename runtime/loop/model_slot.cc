#include "runtime/loop/model_slot.h"

#include <cstdio>
#include <string>

#include "runtime/loop/model_loader.h"

namespace aprt {

void ModelSlot::service() {
  if (retired_.exchange(nullptr, std::memory_order_acq_rel)) {
    engine_.swap(spare_);  // engine_: the model now running; spare_: the old one
    spare_.reset();
    ++reloads_;
    std::fprintf(stderr, "aprt run: model reloaded: %s (%s kernels); reload %llu\n",
                 config_.model.c_str(), engine_->isa(), static_cast<unsigned long long>(reloads_));
  }
  if (!reload_requested_.exchange(false, std::memory_order_acq_rel)) return;
  if (spare_) {
    std::fprintf(stderr, "aprt run: reload requested while one is switching; ignored\n");
    return;
  }
  std::string note;
  auto next = load_model(model_request(config_), &note);
  Status fits = next ? reload_compatible(engine_->meta(), next.value()->meta()) : ok();
  if (!next || !fits) {
    ++refused_;
    std::fprintf(stderr, "aprt run: reload refused, the running model stays: %s\n",
                 next ? fits.error().message() : next.error().message());
    return;
  }
  if (!note.empty())
    std::fprintf(stderr, "aprt run: %s: %s\n", config_.model.c_str(), note.c_str());
  spare_ = std::move(next.value());
  pending_.store(spare_.get(), std::memory_order_release);
}

void ModelSlot::finish() {
  service();
  if (pending_.exchange(nullptr)) spare_.reset();
}

}  // namespace aprt
