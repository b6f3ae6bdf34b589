// A DeepLoc-layout sequence as a frame source, paced like a camera: at a
// fixed rate, at the recorded rate (times.txt), or as fast as frames are
// taken (rate 0: the next frame is decoded only once the consumer took the
// previous one, so a demo loses no frame). Optionally loops.
#pragma once

#include <atomic>
#include <memory>

#include "drivers/frame/frame_slot.h"
#include "drivers/frame/frame_source.h"
#include "drivers/replay/deeploc_replay.h"

namespace aprt {

struct ReplayPacing {
  double rate_hz = 10.0;  // 0: as fast as the consumer
  bool recorded = false;  // use times.txt
  bool loop = false;
  uint64_t max_frames = 0;  // end of stream after this many frames (loops included); 0: no limit
};

class ReplaySource final : public FrameSource {
 public:
  static Expected<std::unique_ptr<ReplaySource>> open(const char* folder, const ReplayPacing& p);

  const char* name() const override { return "replay"; }
  size_t max_frame_bytes() const override { return replay_->frame_bytes(); }
  Status start() override;
  SourceResult next(FrameBuffer* dst, int64_t timeout_ns) override;
  void stop() override {}
  const Error& error() const override { return error_; }

  const DeeplocReplay& replay() const { return *replay_; }
  // For rate 0: the slot whose consumption paces the replay.
  void pace_with(const FrameSlot* slot) { paced_by_ = slot; }
  // Frames the consumer had taken when the replay paced itself (rate 0).
  void note_taken(uint64_t n) { taken_.store(n, std::memory_order_release); }

 private:
  ReplaySource() = default;
  std::unique_ptr<DeeplocReplay> replay_;
  ReplayPacing pacing_;
  Error error_;
  size_t index_ = 0;
  uint64_t sequence_ = 0;
  int64_t start_ns_ = 0;
  double start_time_s_ = 0;
  const FrameSlot* paced_by_ = nullptr;
  std::atomic<uint64_t> taken_{0};
};

}  // namespace aprt
