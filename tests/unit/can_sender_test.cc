// PoseCanSender against a scripted CAN channel: what a real bus does to a
// sender (TX queue full, interface down, vanished, bus-off) is counted and
// recovered from, the alive counter stays consistent, nothing allocates.
#include <gtest/gtest.h>

#include <cerrno>
#include <vector>

#include "drivers/output/can/pose_can_sender.h"
#include "runtime/base/allocation_counter.h"

namespace aprt::can {
namespace {

class FakeChannel final : public Channel {
 public:
  WriteResult write(const Frame& f) noexcept override {
    if (!script.empty()) {
      const WriteResult r = script.front();
      script.erase(script.begin());
      if (r != WriteResult::kSent) {
        last_errno_ = r == WriteResult::kDown    ? ENETDOWN
                      : r == WriteResult::kError ? ENODEV
                                                 : ENOBUFS;
        return r;
      }
    } else if (full) {
      last_errno_ = ENOBUFS;
      return WriteResult::kQueueFull;
    }
    if (sent_count < kMax) sent[sent_count] = f;
    ++sent_count;
    return WriteResult::kSent;
  }
  BusState poll_bus() noexcept override { return bus; }
  bool reopen() noexcept override {
    ++reopen_calls;
    return reopen_ok;
  }
  const char* name() const noexcept override { return "fake"; }

  static constexpr int kMax = 256;
  Frame sent[kMax];
  int sent_count = 0;
  std::vector<WriteResult> script;  // results of the next writes (then: sent)
  bool full = false;
  BusState bus = BusState::kActive;
  bool reopen_ok = true;
  int reopen_calls = 0;
};

PoseSignals pose() {
  PoseSignals s;
  s.state = 1;
  s.valid = true;
  s.x = 12.5;
  s.y = -3.25;
  s.sigma_pos_m = 1;
  s.sigma_yaw_deg = 1;
  return s;
}

constexpr int64_t kMs = 1000000;

TEST(CanSender, SendsFiveFramesPerEstimateWithOneCounter) {
  FakeChannel ch;
  PoseCanSender tx(&ch, SenderOptions{});
  Decoder rx(Ids{});
  for (int i = 0; i < 40; ++i) {
    ASSERT_EQ(tx.send(pose(), i * 100 * kMs), PoseCanSender::Outcome::kSent);
  }
  ASSERT_EQ(ch.sent_count, 200);
  for (int i = 0; i < 200; ++i) {
    EXPECT_EQ(ch.sent[i].data[1] & 0x0F, (i / 5) & 0x0F);
    PoseSignals out;
    rx.feed(ch.sent[i], &out);
  }
  EXPECT_EQ(rx.estimates, 40u);
  EXPECT_EQ(rx.crc_errors + rx.repeated + rx.skipped + rx.incomplete, 0u);
  EXPECT_EQ(tx.stats().estimates, 40u);
  EXPECT_EQ(tx.stats().frames, 200u);
}

TEST(CanSender, FdIsOneFrame) {
  FakeChannel ch;
  SenderOptions o;
  o.fd = true;
  PoseCanSender tx(&ch, o);
  ASSERT_EQ(tx.send(pose(), 0), PoseCanSender::Outcome::kSent);
  ASSERT_EQ(ch.sent_count, 1);
  EXPECT_TRUE(ch.sent[0].fd);
  EXPECT_EQ(ch.sent[0].id, 0x310u);
}

TEST(CanSender, CycleLimitThrottles) {
  FakeChannel ch;
  SenderOptions o;
  o.cycle_ns = 100 * kMs;
  PoseCanSender tx(&ch, o);
  EXPECT_EQ(tx.send(pose(), 0), PoseCanSender::Outcome::kSent);
  EXPECT_EQ(tx.send(pose(), 50 * kMs), PoseCanSender::Outcome::kThrottled);
  EXPECT_EQ(tx.send(pose(), 100 * kMs), PoseCanSender::Outcome::kSent);
  EXPECT_EQ(tx.stats().throttled, 1u);
}

TEST(CanSender, QueueFullRetriesThenDropsAndTheReceiverSeesIt) {
  FakeChannel ch;
  SenderOptions o;
  o.retry_ns = 1 * kMs;
  PoseCanSender tx(&ch, o);
  Decoder rx(Ids{});
  PoseSignals out;
  // One transient ENOBUFS: retried, the estimate goes out whole.
  ch.script = {WriteResult::kSent, WriteResult::kQueueFull};
  ASSERT_EQ(tx.send(pose(), 0), PoseCanSender::Outcome::kSent);
  EXPECT_EQ(tx.stats().queue_full, 1u);
  // A queue that stays full after two frames: the rest is dropped, counted,
  // and the counter still moves on (the frames that went out used it).
  ch.script = {WriteResult::kSent, WriteResult::kSent};
  ch.full = true;
  EXPECT_EQ(tx.send(pose(), 100 * kMs), PoseCanSender::Outcome::kDropped);
  EXPECT_STRNE(tx.problem(), "");
  ch.full = false;
  ASSERT_EQ(tx.send(pose(), 200 * kMs), PoseCanSender::Outcome::kSent);
  EXPECT_STREQ(tx.problem(), "");
  EXPECT_EQ(tx.stats().dropped, 1u);
  EXPECT_EQ(ch.sent_count, 5 + 2 + 5);
  for (int i = 0; i < ch.sent_count; ++i) rx.feed(ch.sent[i], &out);
  EXPECT_EQ(rx.estimates, 2u);
  EXPECT_EQ(rx.incomplete, 1u);  // the two frames of the dropped estimate
  EXPECT_EQ(rx.crc_errors + rx.repeated, 0u);
  EXPECT_EQ(ch.sent[ch.sent_count - 1].data[1] & 0x0F, 2);
}

TEST(CanSender, InterfaceDownIsCountedAndRecoveredWithoutReopen) {
  FakeChannel ch;
  PoseCanSender tx(&ch, SenderOptions{});
  ch.script = {WriteResult::kDown};
  EXPECT_EQ(tx.send(pose(), 0), PoseCanSender::Outcome::kDropped);
  EXPECT_TRUE(tx.stats().link_down);
  EXPECT_EQ(tx.stats().down, 1u);
  EXPECT_EQ(tx.counter(), 0);  // nothing reached the bus: the counter did not move
  EXPECT_EQ(tx.send(pose(), 100 * kMs), PoseCanSender::Outcome::kSent);
  EXPECT_FALSE(tx.stats().link_down);
  EXPECT_EQ(ch.reopen_calls, 0);
}

TEST(CanSender, VanishedInterfaceIsReopenedPerRecoverInterval) {
  FakeChannel ch;
  SenderOptions o;
  o.recover_ns = 1000 * kMs;
  PoseCanSender tx(&ch, o);
  ch.script = {WriteResult::kError};  // ENODEV
  EXPECT_EQ(tx.send(pose(), 0), PoseCanSender::Outcome::kDropped);
  ch.reopen_ok = false;
  EXPECT_EQ(tx.send(pose(), 1000 * kMs), PoseCanSender::Outcome::kDropped);
  EXPECT_EQ(ch.reopen_calls, 1);
  EXPECT_EQ(tx.send(pose(), 1500 * kMs), PoseCanSender::Outcome::kDropped);
  EXPECT_EQ(ch.reopen_calls, 1);  // not before the interval
  ch.reopen_ok = true;
  EXPECT_EQ(tx.send(pose(), 2000 * kMs), PoseCanSender::Outcome::kSent);
  EXPECT_EQ(ch.reopen_calls, 2);
  EXPECT_EQ(tx.stats().reopens, 1u);
}

TEST(CanSender, BusOffHoldsEstimatesAndProbesPerInterval) {
  FakeChannel ch;
  SenderOptions o;
  o.recover_ns = 1000 * kMs;
  PoseCanSender tx(&ch, o);
  ASSERT_EQ(tx.send(pose(), 0), PoseCanSender::Outcome::kSent);
  ch.bus = BusState::kBusOff;
  const int before = ch.sent_count;
  for (int i = 1; i < 10; ++i) {
    EXPECT_EQ(tx.send(pose(), i * 100 * kMs), PoseCanSender::Outcome::kDropped);
  }
  EXPECT_EQ(ch.sent_count, before);  // nothing queued into a bus-off controller
  EXPECT_EQ(tx.stats().bus, BusState::kBusOff);
  EXPECT_EQ(tx.stats().bus_off, 9u);
  EXPECT_STRNE(tx.problem(), "");
  // One probe per recover interval, in case the restart notification was missed.
  EXPECT_EQ(tx.send(pose(), 1100 * kMs), PoseCanSender::Outcome::kSent);
  EXPECT_EQ(tx.send(pose(), 1200 * kMs), PoseCanSender::Outcome::kDropped);
  ch.bus = BusState::kActive;  // the controller restarted
  EXPECT_EQ(tx.send(pose(), 1300 * kMs), PoseCanSender::Outcome::kSent);
  EXPECT_STREQ(tx.problem(), "");
}

TEST(CanSender, SendingAllocatesNothing) {
  FakeChannel ch;
  PoseCanSender tx(&ch, SenderOptions{});
  tx.send(pose(), 0);
  AllocationScope scope;
  for (int i = 1; i < 40; ++i) tx.send(pose(), i * kMs);
  EXPECT_EQ(scope.count(), 0u);
}

}  // namespace
}  // namespace aprt::can
