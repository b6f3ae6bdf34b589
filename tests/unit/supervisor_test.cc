#include "runtime/loop/supervisor.h"

#include <gtest/gtest.h>

#include "runtime/loop/supervision.h"

namespace aprt {
namespace {

constexpr int64_t kMs = 1000000;

Health healthy(int64_t now) {
  Health h;
  h.now_ns = now;
  h.started_ns = 0;
  h.last_frame_ns = now - 10 * kMs;
  h.capture_beat_ns = h.inference_beat_ns = h.publish_beat_ns = now - kMs;
  h.poses = 1;
  return h;
}

Config::Supervisor cfg() {
  Config::Supervisor c;
  c.frame_timeout_ms = 500;
  c.fault_after_s = 2;
  return c;
}

TEST(Supervisor, StartsThenRuns) {
  Supervisor s(cfg());
  Health h = healthy(100 * kMs);
  h.poses = 0;
  h.last_frame_ns = 0;
  EXPECT_EQ(s.step(h), RunState::kStarting);
  h.poses = 1;
  h.last_frame_ns = 90 * kMs;
  EXPECT_EQ(s.step(h), RunState::kRunning);
}

TEST(Supervisor, StaleFramesDegradeThenRecover) {
  Supervisor s(cfg());
  EXPECT_EQ(s.step(healthy(kMs * 1990)), RunState::kRunning);
  Health h = healthy(kMs * 2000);
  h.last_frame_ns = kMs * 1000;  // 1 s old
  EXPECT_EQ(s.step(h), RunState::kDegraded);
  EXPECT_STREQ(s.reason(), "frames stale (sensor stalled?)");
  EXPECT_EQ(s.step(healthy(kMs * 2100)), RunState::kRunning);
}

TEST(Supervisor, FlaggedPosesDegrade) {
  Supervisor s(cfg());
  Health h = healthy(kMs * 1000);
  h.last_flags = kPoseNonFinite;
  EXPECT_EQ(s.step(h), RunState::kDegraded);
  h.last_flags = kPoseDeadlineMissed;
  EXPECT_EQ(s.step(h), RunState::kDegraded);
  EXPECT_STREQ(s.reason(), "inference deadline missed");
  h.last_flags = kPoseOutOfBounds;
  EXPECT_EQ(s.step(h), RunState::kDegraded);
}

// A pose the validity gate withholds is the model's mistake, not the system's:
// RUNNING, with the reason the pose did not go out valid.
TEST(Supervisor, WithheldPosesKeepRunningAndSayWhy) {
  Supervisor s(cfg());
  Health h = healthy(kMs * 1000);
  const struct {
    uint32_t flags;
    const char* reason;
  } cases[] = {
      {kPoseJump, "ok; pose withheld: an implausible jump from the last pose"},
      {kPoseUncertain, "ok; pose withheld: the model (or the pose filter) is not confident enough"},
      {kPoseNoOdometry | kPoseUnconfirmed,
       "ok; pose withheld: no vehicle motion for the pose filter (odometry)"},
      {kPoseInconsistent, "ok; pose withheld: it disagrees with the vehicle's motion"},
      {kPoseUnconfirmed, "ok; pose withheld: no confirmed track yet"},
      {0, "ok"},
  };
  for (const auto& c : cases) {
    h.last_flags = c.flags;
    EXPECT_EQ(s.step(h), RunState::kRunning);
    EXPECT_STREQ(s.reason(), c.reason);
  }
}

TEST(Supervisor, LongDegradationBecomesFault) {
  Supervisor s(cfg());
  Health h = healthy(kMs * 1000);
  h.last_flags = kPoseOutOfBounds;
  EXPECT_EQ(s.step(h), RunState::kDegraded);
  for (int64_t t = 1020; t <= 4000; t += 20) {  // the supervisor's ticks
    h = healthy(kMs * t);
    h.last_flags = kPoseOutOfBounds;
    s.step(h);
  }
  EXPECT_EQ(s.state(), RunState::kFault);
  EXPECT_EQ(s.step(healthy(kMs * 5000)), RunState::kFault);  // terminal
}

TEST(Supervisor, HungStageIsFaultAndStopsThePetting) {
  Supervisor s(cfg());
  Health h = healthy(kMs * 5000);
  h.inference_beat_ns = kMs * 3000;  // 2 s without a beat: hung
  EXPECT_EQ(s.step(h), RunState::kFault);
  EXPECT_FALSE(s.stages_alive());
}

// SIGSTOP for 3 s, then SIGCONT: every beat and the newest frame are 3 s old
// at the next tick, the supervisor's own tick included. That is the whole
// process standing still, not a hung stage: no FAULT, no degradation.
TEST(Supervisor, AWholeProcessFreezeIsNotAHungStage) {
  Supervisor s(cfg());
  EXPECT_EQ(s.step(healthy(kMs * 1000)), RunState::kRunning);
  Health h = healthy(kMs * 4000);
  h.capture_beat_ns = h.inference_beat_ns = h.publish_beat_ns = kMs * 999;
  h.last_frame_ns = kMs * 990;
  h.last_flags = kPoseDeadlineMissed | kPoseStaleFrame;  // the pose in flight during the freeze
  EXPECT_EQ(s.step(h), RunState::kRunning) << s.reason();
  EXPECT_TRUE(s.stages_alive());
  EXPECT_EQ(s.freezes(), 1u);
  EXPECT_EQ(s.step(healthy(kMs * 4020)), RunState::kRunning);  // the stages beat again
}

// After a freeze a stage that still does not beat is hung all the same, two
// frame timeouts later.
TEST(Supervisor, AStageStillSilentAfterAFreezeIsHung) {
  Supervisor s(cfg());
  s.step(healthy(kMs * 1000));
  for (int64_t t = 4000; t <= 5200; t += 20) {
    Health h = healthy(kMs * t);
    h.inference_beat_ns = kMs * 999;  // never again
    s.step(h);
    if (t < 4000 + 2 * 500) {
      EXPECT_EQ(s.state(), RunState::kRunning) << t;
    }
  }
  EXPECT_EQ(s.state(), RunState::kFault);
  EXPECT_STREQ(s.reason(), "a stage stopped beating (hung thread)");
}

TEST(Supervisor, EndOfStreamStops) {
  Supervisor s(cfg());
  Health h = healthy(kMs * 1000);
  h.end_of_stream = true;
  EXPECT_EQ(s.step(h), RunState::kStopping);
}

// A broken invariant in any of the loop's threads ends the process as a
// FAULT: the reason on stderr and exit code 3 (runtime/loop/supervision.h).
TEST(FaultHandler, BrokenInvariantEndsTheProcessAsFault) {
  EXPECT_EXIT(
      {
        install_fault_handler(false);
        APRT_ENFORCE(1 + 1 == 3, "arena overrun");
      },
      ::testing::ExitedWithCode(kFaultExitCode), "state FAULT \\(fatal: arena overrun at .*");
}

}  // namespace
}  // namespace aprt
