#include "runtime/config/config.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdio>
#include <cstring>
#include <string>

namespace aprt {
namespace {

void expect_refused(const std::string& yaml, const char* fragment) {
  auto c = parse_config(yaml, "test.yaml");
  ASSERT_FALSE(c) << "accepted:\n" << yaml.substr(0, 400);
  EXPECT_NE(std::strstr(c.error().message(), fragment), nullptr) << c.error().message();
}

TEST(Config, ParsesAFullFile) {
  auto c = parse_config(R"(
model: m.aprt
engine: {threads: 2, isa: avx2, cpus: [0, 1]}
source:
  type: replay
  replay: {path: /data/drive, rate_hz: 0, loop: true}
output: {console: false}
supervisor: {rate_hz: 100, frame_timeout_ms: 250, watchdog_device: /dev/watchdog}
sanity: {max_jump_m: 5}
threads:
  inference: {priority: 50, cpu: 1}
  lock_memory: true
)",
                        "test.yaml");
  ASSERT_TRUE(c) << c.error().message();
  EXPECT_EQ(c->model, "m.aprt");
  EXPECT_EQ(c->engine.threads, 2);
  EXPECT_EQ(c->engine.isa, "avx2");
  EXPECT_EQ(c->engine.cpus.size(), 2u);
  EXPECT_EQ(c->source.replay.rate_hz, 0.0);
  EXPECT_TRUE(c->source.replay.loop);
  EXPECT_FALSE(c->output.console);
  EXPECT_EQ(c->supervisor.frame_timeout_ms, 250.0);
  EXPECT_EQ(c->supervisor.watchdog_device, "/dev/watchdog");
  EXPECT_EQ(c->threads.inference.priority, 50);
  EXPECT_EQ(c->threads.inference.cpu, 1);
}

TEST(Config, OutputsAndExtrinsics) {
  auto c = parse_config(R"(
model: m.aprt
source: {replay: {path: d}}
output:
  frame_id: map_ecu
  sigma_position_m: 1.5
  dds: {enabled: true, domain: 7, pose_topic: /sensing/aprt/pose, reliability: best_effort, depth: 5}
  can: {enabled: true, interface: vcan0, fd: true, cycle_ms: 100, ids: {status: 0x200, fd: 0x7ff}}
extrinsics:
  sensor_to_base_link: {xyz: [1.2, 0, 1.55], rpy_deg: [0, 3, 0]}
  map_offset: {xyz: [1000, -2000.5, 0]}
)",
                        "test.yaml");
  ASSERT_TRUE(c) << c.error().message();
  EXPECT_EQ(c->output.frame_id, "map_ecu");
  EXPECT_EQ(c->output.sigma_position_m, 1.5);
  EXPECT_TRUE(c->output.dds.enabled);
  EXPECT_EQ(c->output.dds.domain, 7);
  EXPECT_EQ(c->output.dds.pose_topic, "/sensing/aprt/pose");
  EXPECT_EQ(c->output.dds.reliability, "best_effort");
  EXPECT_EQ(c->output.dds.depth, 5);
  EXPECT_TRUE(c->output.can.fd);
  EXPECT_EQ(c->output.can.interface, "vcan0");
  EXPECT_EQ(c->output.can.cycle_ms, 100.0);
  EXPECT_EQ(c->output.can.ids[0], 0x200);
  EXPECT_EQ(c->output.can.ids[1], 0x301);  // default kept
  EXPECT_EQ(c->output.can.ids[5], 0x7ff);
  EXPECT_EQ(c->extrinsics.sensor_xyz[2], 1.55);
  EXPECT_EQ(c->extrinsics.sensor_rpy_deg[1], 3.0);
  EXPECT_EQ(c->extrinsics.map_offset_xyz[1], -2000.5);
}

TEST(Config, RefusesBadOutputs) {
  expect_refused("model: m\nsource: {replay: {path: d}}\noutput: {can: {ids: {status: 0x800}}}",
                 "test.yaml:3: output.can.ids.status: expected an identifier in [0x0, 0x7ff]");
  expect_refused("model: m\nsource: {replay: {path: d}}\noutput: {can: {ids: {pos_xy: 0x300}}}",
                 "output.can.ids: status and pos_xy share id 0x300");
  expect_refused("model: m\nsource: {replay: {path: d}}\noutput: {dds: {reliability: maybe}}",
                 "output.dds.reliability: 'maybe' is not one of: reliable, best_effort");
  expect_refused(
      "model: m\nsource: {replay: {path: d}}\nextrinsics: {sensor_to_base_link: {xyz: [1, 2]}}",
      "extrinsics.sensor_to_base_link.xyz: expected a list of 3 numbers");
  expect_refused(
      "model: m\nsource: {replay: {path: d}}\nextrinsics: {map_offset: {rpy_deg: [0, 0, x]}}",
      "extrinsics.map_offset.rpy_deg[2]: expected a number");
}

// Every thread's stack (ours and the DDS library's): bounded both ways.
TEST(Config, ThreadStackSize) {
  auto c = parse_config("model: m\nsource: {replay: {path: d}}\nthreads: {stack_kib: 1024}\n", "t");
  ASSERT_TRUE(c) << c.error().message();
  EXPECT_EQ(c->threads.stack_kib, 1024);
  auto d = parse_config("model: m\nsource: {replay: {path: d}}\n", "t");
  ASSERT_TRUE(d);
  EXPECT_EQ(d->threads.stack_kib, 512);
  expect_refused("model: m\nsource: {replay: {path: d}}\nthreads: {stack_kib: 64}\n",
                 "threads.stack_kib: expected an integer in [128, 65536]");
}

// A live source keeps output.records poses for the summary (preallocated,
// and locked with lock_memory): bounded, 65536 unless set.
TEST(Config, PoseRecordsOfALiveSource) {
  auto c = parse_config("model: m\nsource: {replay: {path: d}}\noutput: {records: 4096}\n", "t");
  ASSERT_TRUE(c) << c.error().message();
  EXPECT_EQ(c->output.records, 4096);
  auto d = parse_config("model: m\nsource: {replay: {path: d}}\n", "t");
  ASSERT_TRUE(d);
  EXPECT_EQ(d->output.records, 65536);
  expect_refused("model: m\nsource: {replay: {path: d}}\noutput: {records: 100}\n",
                 "output.records: expected an integer in [1024, 16777216]");
}

TEST(Config, RecordedRate) {
  auto c = parse_config("model: m\nsource: {replay: {path: d, rate_hz: recorded}}\n", "t");
  ASSERT_TRUE(c) << c.error().message();
  EXPECT_TRUE(c->source.replay.recorded);
}

TEST(Config, ReplayFrameLimit) {
  auto c = parse_config("model: m\nsource: {replay: {path: d, frames: 40}}\n", "t");
  ASSERT_TRUE(c) << c.error().message();
  EXPECT_EQ(c->source.replay.frames, 40);
  expect_refused("model: m\nsource: {replay: {path: d, frames: -1}}\n", "source.replay.frames");
}

TEST(Config, DeviceFrameLimitsAndDiscoveryWait) {
  auto c = parse_config(
      "model: m\nsource: {type: v4l2, v4l2: {frames: 25}, libcamera: {frames: 30}, "
      "pointcloud2: {frames: 12}}\n"
      "output: {dds: {discovery_wait_ms: 0}}\n",
      "t");
  ASSERT_TRUE(c) << c.error().message();
  EXPECT_EQ(c->source.v4l2.frames, 25);
  EXPECT_EQ(c->source.libcamera.frames, 30);
  EXPECT_EQ(c->source.pointcloud2.frames, 12);
  EXPECT_EQ(c->output.dds.discovery_wait_ms, 0);
  auto d = parse_config("model: m\nsource: {type: v4l2}\n", "t");
  ASSERT_TRUE(d) << d.error().message();
  EXPECT_EQ(d->output.dds.discovery_wait_ms, 1500);
  expect_refused("model: m\nsource: {libcamera: {frames: -1}}\n", "source.libcamera.frames");
  expect_refused("model: m\nsource: {v4l2: {frames: x}}\n", "source.v4l2.frames");
  expect_refused("model: m\noutput: {dds: {discovery_wait_ms: 20000}}\n",
                 "output.dds.discovery_wait_ms");
}

TEST(Config, FaultInjectionAndSigning) {
  auto c = parse_config(
      "model: m\nsource: {replay: {path: d}}\nfault_injection:\n"
      "  - {fault: camera_stall, at_frame: 20, duration_ms: 700}\n"
      "  - {fault: nan_output, at_frame: 3, count: 4}\n"
      "model_signing: {public_key: k.pub, required: true}\n",
      "t");
  ASSERT_TRUE(c) << c.error().message();
  ASSERT_EQ(c->fault_injection.size(), 2u);
  EXPECT_EQ(c->fault_injection[0].kind, FaultKind::kCameraStall);
  EXPECT_DOUBLE_EQ(c->fault_injection[0].duration_ms, 700);
  EXPECT_EQ(c->fault_injection[1].count, 4u);
  EXPECT_TRUE(c->model_signing.required);
  expect_refused("model: m\nsource: {replay: {path: d}}\nfault_injection: [{fault: meteor}]\n",
                 "fault_injection[0].fault: 'meteor' is not one of");
  expect_refused(
      "model: m\nsource: {replay: {path: d}}\nfault_injection: [{fault: camera_stall}]\n",
      "fault_injection[0].duration_ms: required (> 0) for camera_stall");
  expect_refused("model: m\nsource: {replay: {path: d}}\nfault_injection: {fault: x}\n",
                 "expected a list of faults");
  expect_refused("model: m\nsource: {replay: {path: d}}\nmodel_signing: {required: true}\n",
                 "model_signing.required needs model_signing.public_key");
}

// The files the repository and the package ship must stay valid as the schema grows.
TEST(Config, Cameras) {
  auto c = parse_config(R"(
model: m.aprt
cameras:
  - name: front
    source: {type: v4l2, v4l2: {device: /dev/video0, format: MJPEG}}
    sensor_to_base_link: {xyz: [1.5, 0, 1.6]}
  - name: left
    source: {type: v4l2, v4l2: {device: /dev/video1}}
    sensor_to_base_link: {xyz: [1.3, 0.6, 1.6], rpy_deg: [0, 0, 60]}
fusion: {max_position_spread_m: 3, min_agreeing: 2, max_frame_skew_ms: 15}
)",
                        "test.yaml");
  ASSERT_TRUE(c) << c.error().message();
  ASSERT_EQ(c->cameras.size(), 2u);
  EXPECT_EQ(c->cameras[1].name, "left");
  EXPECT_EQ(c->cameras[1].source.v4l2.device, "/dev/video1");
  EXPECT_EQ(c->cameras[1].sensor_rpy_deg[2], 60.0);
  EXPECT_EQ(c->fusion.min_agreeing, 2);
  EXPECT_EQ(c->fusion.max_frame_skew_ms, 15.0);
  // The first camera is mirrored into the single-camera fields.
  EXPECT_EQ(c->source.type, SourceType::kV4l2);
  EXPECT_EQ(c->source.v4l2.format, "MJPEG");
  EXPECT_EQ(c->extrinsics.sensor_xyz[0], 1.5);
  EXPECT_EQ(camera_list(*c).size(), 2u);

  auto one = parse_config("model: m\nsource: {replay: {path: /d}}\n", "t.yaml");
  ASSERT_TRUE(one);
  ASSERT_EQ(camera_list(*one).size(), 1u);
  EXPECT_EQ(camera_list(*one)[0].source.replay.path, "/d");

  const char* cam = "  - name: a\n    source: {replay: {path: /d}}\n";
  expect_refused((std::string("model: m\nsource: {replay: {path: /d}}\ncameras:\n") + cam).c_str(),
                 "give either `source` (one camera) or `cameras`");
  expect_refused((std::string("model: m\ncameras:\n") + cam + cam).c_str(),
                 "cameras[1].name: 'a' is used twice");
  expect_refused("model: m\ncameras:\n  - name: a\n", "cameras[0].source: required");
  expect_refused("model: m\ncameras:\n  - source: {replay: {path: /d}}\n",
                 "cameras[0].name: required");
  expect_refused("model: m\ncameras:\n  - name: a\n    source: {type: replay}\n",
                 "cameras[0].source.replay.path: required");
  expect_refused("model: m\ncameras:\n  - name: a\n    source: {replay: {path: /d, fps: 3}}\n",
                 "test.yaml:4: cameras[0].source.replay.fps: unknown key");
  expect_refused(
      (std::string("model: m\nextrinsics: {sensor_to_base_link: {xyz: [1, 0, 0]}}\ncameras:\n") +
       cam)
          .c_str(),
      "each camera has its own sensor_to_base_link");
  std::string nine = "model: m\ncameras:\n";
  for (int i = 0; i < 9; ++i) {
    nine += "  - name: c" + std::to_string(i) + "\n    source: {replay: {path: /d}}\n";
  }
  expect_refused(nine.c_str(), "at most 8 cameras");
  expect_refused("model: m\ncameras: []\n", "cameras: expected a list of cameras");
  expect_refused("model: m\nsource: {replay: {path: /d}}\nfusion: {min_agreeing: 0}\n",
                 "fusion.min_agreeing: expected an integer in [1, 8]");
}

TEST(Config, Libcamera) {
  auto c = parse_config(
      "model: m\nsource:\n  type: libcamera\n  libcamera: {camera: \"0\", width: 1280, height: "
      "720, "
      "format: NV12, role: video, fps: 20, buffers: 6}\n",
      "test.yaml");
  ASSERT_TRUE(c) << c.error().message();
  EXPECT_EQ(c->source.type, SourceType::kLibcamera);
  EXPECT_EQ(c->source.libcamera.camera, "0");
  EXPECT_EQ(c->source.libcamera.width, 1280);
  EXPECT_EQ(c->source.libcamera.format, "NV12");
  EXPECT_EQ(c->source.libcamera.role, "video");
  EXPECT_EQ(c->source.libcamera.fps, 20);
  EXPECT_EQ(c->source.libcamera.buffers, 6);
  expect_refused("model: m\nsource: {type: libcamera, libcamera: {role: raw}}\n",
                 "source.libcamera.role: 'raw' is not one of: viewfinder, video, still");
  expect_refused("model: m\nsource: {type: libcamera, libcamera: {device: /dev/video0}}\n",
                 "source.libcamera.device: unknown key");
}

TEST(Config, LidarSources) {
  auto c = parse_config(R"(
model: points.aprt
source:
  type: pointcloud2
  pointcloud2: {topic: /sensing/lidar/top/pointcloud, domain: 3, reliable: true, depth: 2}
  lidar:
    max_points: 150000
    region: {x_min: -100, x_max: 100, z_min: -5, z_max: 10}
    min_points: 500
)",
                        "test.yaml");
  ASSERT_TRUE(c) << c.error().message();
  EXPECT_TRUE(c->source.lidar_source());
  EXPECT_EQ(c->source.pointcloud2.topic, "/sensing/lidar/top/pointcloud");
  EXPECT_EQ(c->source.pointcloud2.domain, 3);
  EXPECT_TRUE(c->source.pointcloud2.reliable);
  EXPECT_EQ(c->source.pointcloud2.depth, 2);
  EXPECT_EQ(c->source.lidar.max_points, 150000);
  EXPECT_EQ(c->source.lidar.region[0], -100.0);
  EXPECT_EQ(c->source.lidar.region[3], 200.0);  // y_max: the default
  EXPECT_EQ(c->source.lidar.region[5], 10.0);
  EXPECT_EQ(c->source.lidar.min_points, 500);
  auto r = parse_config("model: m.aprt\nsource: {type: lidar_replay, replay: {path: /d}}\n", "t");
  ASSERT_TRUE(r) << r.error().message();
  EXPECT_TRUE(r->source.lidar_source());
  expect_refused("model: m\nsource: {type: lidar_replay}\n",
                 "source.replay.path is required for a lidar_replay source");
  expect_refused("model: m\nsource: {type: pointcloud2, lidar: {max_points: 0}}\n",
                 "source.lidar.max_points: expected an integer in [1, 4194304]");
  expect_refused("model: m\nsource: {type: pointcloud2, lidar: {region: {x_min: 300}}}\n",
                 "source.lidar.region: every axis needs min < max");
  expect_refused("model: m\nsource: {type: pointcloud2, pointcloud2: {qos: fast}}\n",
                 "source.pointcloud2.qos");
  expect_refused("model: m\nsource: {type: velodyne}\n", "lidar_replay, pointcloud2");
  expect_refused(R"(
model: m
cameras:
  - name: front
    source: {type: replay, replay: {path: /a}}
  - name: roof
    source: {type: pointcloud2}
)",
                 "cameras.roof: a LiDAR source (pointcloud2) is one sensor");
}

TEST(Config, PoseFilter) {
  auto c = parse_config(
      "model: m\nsource: {replay: {path: d}}\nsanity:\n  filter: {enabled: true, "
      "distance_noise: 0.1, max_radius_m: 10, confirm: 3, position_sigma_scale: 0.6,\n"
      "    estimate_max_radius_m: 120, estimate_max_yaw_deg: 25, estimate_sigma_scale: 0.35,\n"
      "    disagreement_frames: 25, place_sigma_m: 1.5, place_length_m: 8}\n",
      "test.yaml");
  ASSERT_TRUE(c) << c.error().message();
  EXPECT_TRUE(c->sanity.filter.enabled);
  EXPECT_EQ(c->sanity.filter.distance_noise, 0.1);
  EXPECT_EQ(c->sanity.filter.max_radius_m, 10.0);
  EXPECT_EQ(c->sanity.filter.confirm, 3);
  EXPECT_EQ(c->sanity.filter.position_sigma_scale, 0.6);
  EXPECT_EQ(c->sanity.filter.estimate_max_radius_m, 120.0);
  EXPECT_EQ(c->sanity.filter.estimate_max_yaw_deg, 25.0);
  EXPECT_EQ(c->sanity.filter.estimate_sigma_scale, 0.35);
  EXPECT_EQ(c->sanity.filter.disagreement_frames, 25);
  EXPECT_EQ(c->sanity.filter.place_sigma_m, 1.5);
  EXPECT_EQ(c->sanity.filter.place_length_m, 8.0);
  expect_refused("model: m\nsource: {replay: {path: d}}\nsanity: {filter: {place_length_m: 0}}\n",
                 "place_length_m");
  expect_refused(
      "model: m\nsource: {replay: {path: d}}\nsanity: {filter: {disagreement_frames: -1}}\n",
      "disagreement_frames");
  expect_refused(
      "model: m\nsource: {replay: {path: d}}\nsanity: {filter: {estimate_sigma_scale: 0}}\n",
      "estimate_sigma_scale");
  EXPECT_FALSE(parse_config("model: m\nsource: {replay: {path: d}}\n", "t")->sanity.filter.enabled);
  // A live camera needs the vehicle's odometry from the bus (odometry.source dds).
  expect_refused("model: m\nsource: {type: v4l2}\nsanity: {filter: {enabled: true}}\n",
                 "sanity.filter needs the vehicle's odometry");
  auto live = parse_config(
      "model: m\nsource: {type: v4l2}\nsanity: {filter: {enabled: true}}\n"
      "odometry: {source: dds, topic: /twist, domain: 3}\n",
      "test.yaml");
  ASSERT_TRUE(live) << live.error().message();
  EXPECT_EQ(live->odometry.topic, "/twist");
  EXPECT_EQ(live->odometry.domain, 3);
  expect_refused("model: m\nsource: {replay: {path: d}}\nodometry: {source: flexray}\n",
                 "odometry.source: 'flexray' is not one of replay");
  // The vehicle's own bus: its DBC and the two signals in it.
  auto bus = parse_config(
      "model: m\nsource: {type: v4l2}\nsanity: {filter: {enabled: true}}\n"
      "odometry:\n  source: can\n  can: {interface: vcan0, dbc: car.dbc, speed: ESP.Speed,\n"
      "        yaw_rate: ESP.Yaw, yaw_rate_unit: deg/s, yaw_rate_clockwise: true,\n"
      "        max_pair_age_ms: 40, direction: TCU.Gear, reverse_values: [1, 9]}\n",
      "test.yaml");
  ASSERT_TRUE(bus) << bus.error().message();
  EXPECT_EQ(bus->odometry.can.interface, "vcan0");
  EXPECT_EQ(bus->odometry.can.dbc, "car.dbc");
  EXPECT_EQ(bus->odometry.can.speed, "ESP.Speed");
  EXPECT_EQ(bus->odometry.can.yaw_rate, "ESP.Yaw");
  EXPECT_EQ(bus->odometry.can.speed_unit, "");
  EXPECT_EQ(bus->odometry.can.yaw_rate_unit, "deg/s");
  EXPECT_TRUE(bus->odometry.can.yaw_rate_clockwise);
  EXPECT_EQ(bus->odometry.can.max_pair_age_ms, 40);
  EXPECT_EQ(bus->odometry.can.direction, "TCU.Gear");
  EXPECT_EQ(bus->odometry.can.reverse_values, (std::vector<int>{1, 9}));
  expect_refused("model: m\nsource: {type: v4l2}\nodometry: {can: {reverse_values: [R]}}\n",
                 "odometry.can.reverse_values[0]");
  expect_refused("model: m\nsource: {type: v4l2}\nodometry: {source: can, can: {speed: A.B}}\n",
                 "odometry.source can needs odometry.can.dbc (the vehicle's DBC file)");
  expect_refused(
      "model: m\nsource: {type: v4l2}\nodometry: {source: can, can: {dbc: x.dbc, speed: A.B}}\n",
      "odometry.source can needs odometry.can.yaw_rate (MESSAGE.SIGNAL");
  expect_refused("model: m\nsource: {type: v4l2}\nodometry: {can: {speeed: A.B}}\n", "speeed");
  expect_refused(
      "model: m\nsource: {replay: {path: d}}\nfusion: {companion: c.yaml}\n"
      "sanity: {filter: {enabled: true}}\n",
      "sanity.filter with fusion.companion");
  expect_refused("model: m\nsource: {replay: {path: d}}\nsanity: {filter: {gate_chi2: 0}}\n",
                 "sanity.filter.gate_chi2");
}

TEST(Config, ShippedConfigurationsParse) {
  for (const char* name : {"config/default.yaml", "config/aprt.yaml", "config/autoware.yaml"}) {
    auto c = load_config(std::string(APRT_SOURCE_DIR) + "/" + name);
    ASSERT_TRUE(c) << name << ": " << c.error().message();
  }
  auto ecu = load_config(std::string(APRT_SOURCE_DIR) + "/config/aprt.yaml");
  EXPECT_EQ(ecu->source.type, SourceType::kV4l2);
  EXPECT_TRUE(ecu->output.can.enabled);
  EXPECT_TRUE(ecu->output.dds.enabled);
  EXPECT_EQ(ecu->model[0], '/');  // the service's working directory is not the data folder
  auto demo = load_config(std::string(APRT_SOURCE_DIR) + "/config/default.yaml");
  EXPECT_TRUE(demo->sanity.filter.enabled);  // the demo drive has odometry.txt
  auto autoware = load_config(std::string(APRT_SOURCE_DIR) + "/config/autoware.yaml");
  EXPECT_TRUE(autoware->sanity.filter.enabled);  // on the vehicle's twist topic
  EXPECT_EQ(autoware->odometry.source, "dds");
}

TEST(Config, RefusesWithKeyPathAndLine) {
  expect_refused("model: m\nsource:\n  replay:\n    path: d\n    rate_hz: fast\n",
                 "test.yaml:5: source.replay.rate_hz: expected a number in [0, 1000], got 'fast'");
  expect_refused("model: m\nsource: {replay: {path: d}}\nengine:\n  thread: 2\n",
                 "test.yaml:4: engine.thread: unknown key");
  expect_refused("model: m\nsource: {replay: {path: d}}\nengine: {threads: 99}\n",
                 "engine.threads: expected an integer in [1, 16], got '99'");
  expect_refused("model: m\nsource: {replay: {path: d}}\nengine: {isa: sse}\n",
                 "engine.isa: 'sse' is not one of");
  expect_refused("model: m\nsource: {replay: {path: d}}\noutput: {console: yes please}\n",
                 "output.console: expected true or false");
  expect_refused("model: m\nsource: {replay: {path: d}}\nthreads: {inference: {priority: 120}}\n",
                 "threads.inference.priority");
  expect_refused("model: m\nmodel: n\n", "key 'model' appears twice");
  expect_refused("source: {replay: {path: d}}\n", "'model'");
  expect_refused("model: m\n", "source.replay.path is required");
  expect_refused("model: [unclosed\n", "YAML syntax error");
  expect_refused("- a\n- b\n", "must be a mapping");
}

// The hostile configurations of docs/hostile_input.md, each refused with its
// reason (a stack overflow, an endless read, minutes of work, or a silently
// wrong value before).
TEST(Config, HostileConfigurationsAreRefused) {
  const std::string base = "model: m\nsource: {replay: {path: d}}\n";
  expect_refused(base + "x: " + std::string(10000, '[') + "\n", "nesting deeper than 32 levels");
  expect_refused(base + "output: {frame_id: !!str 1}\n" + "sanity: {max_jump_m: !!str 5}\n",
                 "sanity.max_jump_m: expected a number");  // a string, never a number
  expect_refused(base + "output: {frame_id: !custom map}\n", "YAML tags are not supported");
  expect_refused("model: m\nsource: {replay: {path: d, rate_hz: 0x10}}\n",
                 "expected a number in [0, 1000], got '0x10'");
  expect_refused(base + "sanity: {max_jump_m: nan}\n", "got 'nan'");
  expect_refused(base + "engine: {cpus: [1023]}\n", "engine.cpus[0]: expected an integer in [0,");
  expect_refused(base + "threads: {capture: {cpu: 4096}}\n", "threads.capture.cpu");
  expect_refused(base + "output: {frame_id: \"\"}\n", "output.frame_id: must not be empty");
  // Many keys: the duplicate check is constant time per key (it was quadratic).
  std::string many = base + "extra:\n";
  for (int i = 0; i < 50000; ++i) many += "  k" + std::to_string(i) + ": 1\n";
  many += "  k7: 2\n";
  expect_refused(many, "key 'k7' appears twice");
}

TEST(Config, FilesThatAreNotFilesAreRefused) {
  auto zero = load_config("/dev/zero");
  ASSERT_FALSE(zero);
  EXPECT_NE(std::string(zero.error().message()).find("a character device"), std::string::npos)
      << zero.error().message();
  const std::string fifo = ::testing::TempDir() + "config.fifo";
  std::remove(fifo.c_str());
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  auto f = load_config(fifo);  // returns at once: the FIFO is not read
  ASSERT_FALSE(f);
  EXPECT_NE(std::string(f.error().message()).find("a FIFO"), std::string::npos);
  const std::string big = ::testing::TempDir() + "big.yaml";
  std::FILE* b = std::fopen(big.c_str(), "w");
  ASSERT_NE(b, nullptr);
  std::fseek(b, 2 << 20, SEEK_SET);
  std::fputc('\n', b);
  std::fclose(b);
  auto large = load_config(big);
  ASSERT_FALSE(large);
  EXPECT_NE(std::string(large.error().message()).find("more than the 1048576"), std::string::npos)
      << large.error().message();
}

}  // namespace
}  // namespace aprt
