// Several cameras through one loop (config `cameras`, runtime/pose/pose_fusion.h),
// on the shipped model and demo drive: cameras that see the same thing agree
// and give exactly the single-camera pose; a camera whose mounting says it
// looks elsewhere is rejected as an outlier; two cameras that disagree give
// no valid pose; a camera that stops is missing and the others carry on; and
// the whole cycle allocates nothing after the first pose.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>

#include "runtime/base/allocation_counter.h"
#include "runtime/config/config.h"
#include "runtime/loop/runtime.h"

namespace aprt {
namespace {

std::string shipped_root() {
#ifdef APRT_SOURCE_DIR
  const std::string root = APRT_SOURCE_DIR;
  if (access((root + "/model_bin/town_64.aprt").c_str(), R_OK) == 0) return root;
#endif
  return "";
}

Config::Camera camera(const std::string& name, const std::string& root, int frames,
                      double yaw_deg = 0) {
  Config::Camera cam;
  cam.name = name;
  cam.source.type = SourceType::kReplay;
  cam.source.replay.path = root + "/data/demo_drive";
  cam.source.replay.rate_hz = 0;  // as fast as inference takes frames: none dropped
  cam.source.replay.frames = frames;
  cam.sensor_xyz[0] = 1.2;
  cam.sensor_xyz[2] = 1.5;
  cam.sensor_rpy_deg[2] = yaw_deg;
  return cam;
}

Config base(const std::string& root) {
  Config c;
  c.model = root + "/model_bin/town_64.aprt";
  c.output.console = false;
  c.output.summary = false;
  c.sanity.max_jump_m = 0;
  c.sanity.bounds_margin = 1;
  c.sanity.track.enabled = false;  // fusion is under test, not the validity gate
  c.supervisor.inference_deadline_ms = 5000;
  c.supervisor.frame_timeout_ms = 5000;
  c.supervisor.systemd = false;
  c.threads.lock_memory = false;
  // Replays decode PNGs on their capture threads; a sanitizer build on two
  // cores may take a while for the third camera's frame.
  c.fusion.max_frame_skew_ms = 2000;
  return c;
}

// Makes `c` the configuration of these cameras (the first mirrored into source).
void use(Config* c, std::vector<Config::Camera> cams) {
  c->cameras = std::move(cams);
  c->source = c->cameras[0].source;
  for (int k = 0; k < 3; ++k) {
    c->extrinsics.sensor_xyz[k] = c->cameras[0].sensor_xyz[k];
    c->extrinsics.sensor_rpy_deg[k] = c->cameras[0].sensor_rpy_deg[k];
  }
}

struct Outcome {
  int code = -1;
  RunStats stats;
  BasePose last{};
};

Outcome run(const Config& c) {
  Outcome o;
  auto rt = Runtime::create(c);
  EXPECT_TRUE(rt) << rt.error().message();
  if (!rt) return o;
  o.code = rt.value()->run();
  o.stats = rt.value()->stats();
  o.last = rt.value()->outputs().last_base_pose();
  return o;
}

TEST(MultiCamera, AgreeingCamerasGiveTheSingleCameraPoseAndAnOutlierIsRejected) {
  const std::string root = shipped_root();
  if (root.empty()) GTEST_SKIP() << "no shipped model";
  Config one = base(root);
  use(&one, {camera("front", root, 30)});
  one.cameras.clear();  // the plain single-camera configuration
  const Outcome single = run(one);
  ASSERT_EQ(single.code, 0);
  ASSERT_EQ(single.stats.poses, 30u);

  Config three = base(root);
  use(&three, {camera("front", root, 30), camera("front_copy", root, 30),
               camera("turned", root, 30, 60.0)});
  const Outcome fused = run(three);
  ASSERT_EQ(fused.code, 0);
  EXPECT_EQ(fused.stats.poses, 30u);
  EXPECT_EQ(fused.stats.poses_flagged, 0u);
  EXPECT_EQ(fused.stats.fusion_no_quorum, 0u);
  ASSERT_EQ(fused.stats.cameras.size(), 3u);
  EXPECT_EQ(fused.stats.cameras[0].outliers, 0u);
  EXPECT_EQ(fused.stats.cameras[1].outliers, 0u);
  // Its images are the front camera's, its mounting says 60 degrees to the left.
  EXPECT_EQ(fused.stats.cameras[2].outliers, 30u);
  for (const RunStats::Camera& cam : fused.stats.cameras) {
    EXPECT_EQ(cam.frames, 30u);
    EXPECT_EQ(cam.missing, 0u);
  }
  // Two identical estimates fused: the single camera's pose on the last frame.
  EXPECT_LT((fused.last.position - single.last.position).norm(), 1e-9);
  EXPECT_LT(fused.last.orientation.angularDistance(single.last.orientation), 1e-9);
}

TEST(MultiCamera, TwoCamerasThatDisagreeGiveNoValidPose) {
  const std::string root = shipped_root();
  if (root.empty()) GTEST_SKIP() << "no shipped model";
  Config c = base(root);
  use(&c, {camera("front", root, 20), camera("turned", root, 20, 90.0)});
  const Outcome o = run(c);
  EXPECT_EQ(o.stats.poses, 20u);
  EXPECT_EQ(o.stats.fusion_no_quorum, 20u);
  EXPECT_EQ(o.stats.poses_flagged, 20u);  // published flagged, never as valid
}

TEST(MultiCamera, ACameraThatStopsIsMissingAndTheOthersCarryOn) {
  const std::string root = shipped_root();
  if (root.empty()) GTEST_SKIP() << "no shipped model";
  Config c = base(root);
  c.fusion.max_frame_skew_ms = 200;  // the third camera's replay has ended: do not wait long
  use(&c, {camera("front", root, 30), camera("front_copy", root, 30), camera("short", root, 10)});
  const Outcome o = run(c);
  ASSERT_EQ(o.code, 0);
  EXPECT_EQ(o.stats.poses, 30u);
  EXPECT_EQ(o.stats.fusion_no_quorum, 0u);  // two of two usable agree
  EXPECT_EQ(o.stats.poses_flagged, 0u);
  EXPECT_EQ(o.stats.cameras[2].frames, 10u);
  EXPECT_EQ(o.stats.cameras[2].missing, 20u);
}

TEST(MultiCamera, NoAllocationAfterTheFirstPose) {
  const std::string root = shipped_root();
  if (root.empty()) GTEST_SKIP() << "no shipped model";
  Config c = base(root);
  use(&c, {camera("front", root, 40), camera("left", root, 40), camera("turned", root, 40, -60.0)});
  auto rt = Runtime::create(c);
  ASSERT_TRUE(rt) << rt.error().message();
  rt.value()->set_allocation_counter(allocation_count, allocation_counter_covers_malloc());
  ASSERT_EQ(rt.value()->run(), 0);
  const std::string json = ::testing::TempDir() + "multi_camera_timing.json";
  ASSERT_TRUE(rt.value()->write_timing_report(json.c_str()));
  std::ifstream in(json);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"allocations_after_first_pose\": 0,"), std::string::npos) << text;
  std::remove(json.c_str());
  std::remove((json.substr(0, json.size() - 5) + ".csv").c_str());
}

}  // namespace
}  // namespace aprt
