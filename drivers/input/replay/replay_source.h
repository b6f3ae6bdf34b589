// A DeepLoc-layout sequence as a frame source, paced like a camera: at a
// fixed rate, at the recorded rate (times.txt), or as fast as frames are
// taken (rate 0: the next frame is decoded only once the consumer took the
// previous one, so a demo loses no frame). Optionally loops. With the
// sequence's odometry.txt each frame carries its odometry reading.
#pragma once

#include <atomic>
#include <memory>

#include "drivers/input/frame_slot.h"
#include "drivers/input/frame_source.h"
#include "drivers/input/replay/deeploc_replay.h"
#include "drivers/input/replay/replay_pacer.h"

namespace aprt {

class ReplaySource final : public FrameSource {
 public:
  static Expected<std::unique_ptr<ReplaySource>> open(const char* folder, const ReplayPacing& p);

  const char* name() const override { return "replay"; }
  size_t max_frame_bytes() const override { return replay_->frame_bytes(); }
  bool has_odometry() const override { return replay_->has_odometry(); }
  Status start() override;
  SourceResult next(FrameBuffer* dst, int64_t timeout_ns) override;
  void stop() override {}
  const Error& error() const override { return error_; }

  void pace_with(const FrameSlot* slot) override { pacer_.pace_with(slot); }
  void note_taken(uint64_t n) override { pacer_.note_taken(n); }

  const DeeplocReplay& replay() const { return *replay_; }

 private:
  ReplaySource() = default;
  std::unique_ptr<DeeplocReplay> replay_;
  ReplayPacer pacer_;
  Error error_;
  size_t previous_ = 0;  // the index of the frame delivered last
  bool have_previous_ = false;
  uint32_t loops_ = 0;
};

}  // namespace aprt
