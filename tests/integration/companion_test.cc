// A second sensor with its own model in the loop (runtime/loop/companion.h):
// the tiny camera model on a short drive's images, the tiny BEV model on the
// same drive's scans as the companion. Both run, every pose says whose
// estimate it is, the counts add up, nothing is allocated after the first
// pose; a companion that cannot open refuses the run with its reason.
//
// Needs APRT_RUN_FIXTURES (the tiny golden models and run_lidar/, a drive
// with images and scans).
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "runtime/base/allocation_counter.h"
#include "runtime/config/config.h"
#include "runtime/loop/runtime.h"
#include "tests/support/loop_test_config.h"

namespace aprt {
namespace {

std::string fixtures() {
  const char* d = std::getenv("APRT_RUN_FIXTURES");
  return d ? d : "";
}

Config sensor_config(const char* model, SourceType type) {
  Config c = test::loop_test_config(fixtures() + "/golden/" + model + "/model.aprt", type,
                                    fixtures() + "/run_lidar");
  c.source.replay.rate_hz = 20;  // both at one rate: frame i and scan i together
  c.output.summary = true;
  return c;
}

TEST(Companion, CameraWithALidarCompanionEndToEnd) {
  if (fixtures().empty()) GTEST_SKIP() << "APRT_RUN_FIXTURES not set";
  Config camera = sensor_config("tiny_op13", SourceType::kReplay);
  camera.extrinsics.sensor_xyz[0] = 1.2;
  camera.extrinsics.sensor_xyz[2] = 1.55;
  camera.fusion.companion = "lidar.yaml";  // what cmd_run loads; here given directly
  // Untrained models: the gate would withhold everything; without it each
  // sensor's estimate is valid unless non-finite, and the fusion decides.
  camera.sanity.track.enabled = false;
  Config lidar = sensor_config("tiny_bev", SourceType::kLidarReplay);
  lidar.extrinsics.sensor_xyz[2] = 1.9;
  lidar.sanity.track.enabled = false;
  lidar.origin = "lidar.yaml";
  auto rt = Runtime::create(camera, &lidar);
  ASSERT_TRUE(rt) << rt.error().message();
  rt.value()->set_allocation_counter(allocation_count, allocation_counter_covers_malloc());
  ASSERT_EQ(rt.value()->run(), 0);
  const RunStats& s = rt.value()->stats();
  // Every frame captured; a slow build (sanitizers) may find a newer frame in
  // the slot before it took the last one (latest wins), so not every frame
  // need become a pose.
  EXPECT_EQ(s.frames_captured, 12u);
  EXPECT_EQ(s.poses + s.frames_dropped, 12u);
  const Companion* co = rt.value()->companion();
  ASSERT_NE(co, nullptr);
  const Companion::Stats& cs = co->stats();
  EXPECT_GT(cs.estimates, 0u);
  EXPECT_LE(cs.estimates, s.poses);
  const uint64_t valid = cs.used[1] + cs.used[2] + cs.used[3];
  EXPECT_EQ(cs.used[0], 0u);  // kNone is never counted as valid
  EXPECT_EQ(valid, s.poses - s.poses_flagged);
  // Two valid estimates that disagree: neither has a valid history longer than
  // the other's by fusion.min_lead_s (1 s; the drive lasts 0.6 s), so each
  // such cycle is withheld as no-quorum, never decided by a coin.
  size_t n = 0, no_quorum = 0;
  const TimingRecord* t = rt.value()->timings(&n);
  ASSERT_EQ(n, s.poses);
  for (size_t i = 0; i < n; ++i) no_quorum += (t[i].flags & kPoseNoQuorum) != 0;
  EXPECT_EQ(no_quorum, cs.disagreements);
  const std::string json = ::testing::TempDir() + "companion_timing.json";
  ASSERT_TRUE(rt.value()->write_timing_report(json.c_str()));
  std::ifstream in(json);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"allocations_after_first_pose\": 0,"), std::string::npos) << text;
}

TEST(Companion, AModelThatDoesNotFitItsSourceRefusesTheRun) {
  if (fixtures().empty()) GTEST_SKIP() << "APRT_RUN_FIXTURES not set";
  Config camera = sensor_config("tiny_op13", SourceType::kReplay);
  Config wrong = sensor_config("tiny_op13", SourceType::kLidarReplay);  // a camera model on scans
  wrong.origin = "companion.yaml";
  auto rt = Runtime::create(camera, &wrong);
  ASSERT_FALSE(rt);
  const std::string m = rt.error().message();
  EXPECT_NE(m.find("fusion.companion companion.yaml"), std::string::npos) << m;
  EXPECT_NE(m.find("gives LiDAR scans"), std::string::npos) << m;
}

}  // namespace
}  // namespace aprt
