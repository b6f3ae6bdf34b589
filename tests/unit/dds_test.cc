// DDS output as a ROS 2 node sees it: a subscriber on the loopback-only
// profile receives PoseWithCovarianceStamped under ROS 2's type name, and the
// serialized sample is byte-identical to a CDR image built here by hand from
// the ROS 2 message definitions (XCDR1, little endian, final). And the LiDAR
// input: PointCloud2 clouds written as a ROS 2 driver writes them arrive
// decoded; the newest wins; a malformed one is counted with its reason.
#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "drivers/dds/dds_domain.h"
#include "drivers/input/pointcloud2/pointcloud2_reader.h"
#include "drivers/input/twist/twist_reader.h"
#include "drivers/output/dds/dds_publisher.h"
#include "ros2_interfaces.h"
#include "runtime/base/allocation_counter.h"
#include "runtime/loop/estimator.h"
#include "runtime/loop/odometry_input.h"

namespace aprt {
namespace {

// A domain of its own per test process, so parallel test runs do not meet.
uint32_t test_domain() {
  return 100 + uint32_t(getpid()) % 100;
}

class CdrWriter {
 public:
  void u32(uint32_t v) { put(&v, 4, 4); }
  void i32(int32_t v) { put(&v, 4, 4); }
  void f64(double v) { put(&v, 8, 8); }
  void str(const char* s) {
    u32(uint32_t(std::strlen(s) + 1));
    bytes.insert(bytes.end(), s, s + std::strlen(s) + 1);
  }
  std::vector<uint8_t> bytes;

 private:
  // Alignment is relative to the start of the payload, after the 4-byte encapsulation header.
  void put(const void* p, size_t n, size_t align) {
    while (bytes.size() % align) bytes.push_back(0);
    const auto* b = static_cast<const uint8_t*>(p);
    bytes.insert(bytes.end(), b, b + n);
  }
};

struct Reader {
  dds_entity_t participant = 0, reader = 0;
  Reader(uint32_t domain, const char* topic, const dds_topic_descriptor_t* desc) {
    participant = dds_create_participant(domain, nullptr, nullptr);
    const dds_entity_t t = dds_create_topic(participant, desc, topic, nullptr, nullptr);
    dds_qos_t* q = dds_create_qos();
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 10);
    reader = dds_create_reader(participant, t, q, nullptr);
    dds_delete_qos(q);
  }
  ~Reader() {
    if (participant > 0) dds_delete(participant);
  }
  bool wait_matched() const {
    for (int i = 0; i < 500; ++i) {
      dds_subscription_matched_status_t st;
      if (dds_get_subscription_matched_status(reader, &st) == DDS_RETCODE_OK &&
          st.current_count > 0)
        return true;
      dds_sleepfor(DDS_MSECS(10));
    }
    return false;
  }
  // Waits up to 5 s for one serialized sample.
  std::vector<uint8_t> take_cdr() const {
    for (int i = 0; i < 500; ++i) {
      ddsi_serdata* sd = nullptr;
      dds_sample_info_t info;
      if (dds_takecdr(reader, &sd, 1, &info, DDS_ANY_STATE) == 1) {
        std::vector<uint8_t> out(ddsi_serdata_size(sd));
        ddsi_serdata_to_ser(sd, 0, out.size(), out.data());
        ddsi_serdata_unref(sd);
        return out;
      }
      dds_sleepfor(DDS_MSECS(10));
    }
    return {};
  }
};

DdsOptions options(const char* topic) {
  DdsOptions o;
  o.domain = test_domain();
  o.loopback_only = true;
  o.pose_topic = topic;
  o.frame_id = "map_ecu";  // 8 bytes with its NUL: exercises the padding before the doubles
  return o;
}

DdsPose make_pose() {
  DdsPose p{};
  p.stamp_ns = 1795000000LL * 1000000000LL + 123456789;
  p.position[0] = 1234.5;
  p.position[1] = -678.25;
  p.position[2] = 1.5;
  p.orientation[0] = 0.9;  // w
  p.orientation[1] = 0.1;
  p.orientation[2] = -0.2;
  p.orientation[3] = 0.3;
  for (int i = 0; i < 36; ++i) p.covariance[i] = (i % 7 == 0) ? 0.25 + i : 0.0;
  return p;
}

TEST(Dds, TypeNameIsRos2s) {
  EXPECT_STREQ(DdsPublisher::pose_type_name(),
               "geometry_msgs::msg::dds_::PoseWithCovarianceStamped_");
}

TEST(Dds, PoseIsByteIdenticalToHandBuiltCdr) {
  auto pub = DdsPublisher::create(options("/aprt/test_pose"));
  ASSERT_TRUE(pub) << pub.error().message();
  Reader r(test_domain(), "rt/aprt/test_pose",
           &geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc);
  ASSERT_GT(r.reader, 0);
  ASSERT_TRUE(r.wait_matched());
  const DdsPose p = make_pose();
  ASSERT_TRUE(pub.value()->publish_pose(p));
  const std::vector<uint8_t> got = r.take_cdr();
  ASSERT_FALSE(got.empty());

  CdrWriter w;
  w.i32(1795000000);  // header.stamp.sec
  w.u32(123456789);   // header.stamp.nanosec
  w.str("map_ecu");   // header.frame_id
  w.f64(1234.5);      // pose.pose.position
  w.f64(-678.25);
  w.f64(1.5);
  w.f64(0.1);  // pose.pose.orientation: x y z w (ROS field order)
  w.f64(-0.2);
  w.f64(0.3);
  w.f64(0.9);
  for (int i = 0; i < 36; ++i) w.f64(p.covariance[i]);
  std::vector<uint8_t> expect = {0x00, 0x01, 0x00, 0x00};  // CDR_LE encapsulation
  expect.insert(expect.end(), w.bytes.begin(), w.bytes.end());
  ASSERT_EQ(got.size(), expect.size());
  EXPECT_EQ(got, expect);
}

TEST(Dds, DiagnosticsCarryTheStatus) {
  DdsOptions o = options("/aprt/test_pose2");
  o.diagnostics_topic = "/aprt_test_diagnostics";
  auto pub = DdsPublisher::create(o);
  ASSERT_TRUE(pub) << pub.error().message();
  Reader r(test_domain(), "rt/aprt_test_diagnostics",
           &diagnostic_msgs_msg_dds__DiagnosticArray__desc);
  ASSERT_TRUE(r.wait_matched());
  const char* keys[2] = {"state", "can"};
  const char* values[2] = {"DEGRADED", "can0 bus-off"};
  ASSERT_TRUE(
      pub.value()->publish_status(5000000000LL, 1, "DEGRADED: frames late", keys, values, 2));
  void* samples[1] = {nullptr};
  dds_sample_info_t info[1];
  int n = 0;
  for (int i = 0; i < 500 && n <= 0; ++i) {
    n = dds_take(r.reader, samples, info, 1, 1);
    if (n <= 0) dds_sleepfor(DDS_MSECS(10));
  }
  ASSERT_EQ(n, 1);
  const auto* a = static_cast<const diagnostic_msgs_msg_dds__DiagnosticArray_*>(samples[0]);
  EXPECT_EQ(a->header.stamp.sec, 5);
  ASSERT_EQ(a->status._length, 1u);
  EXPECT_EQ(a->status._buffer[0].level, 1);
  EXPECT_STREQ(a->status._buffer[0].message, "DEGRADED: frames late");
  ASSERT_EQ(a->status._buffer[0].values._length, 2u);
  EXPECT_STREQ(a->status._buffer[0].values._buffer[1].key, "can");
  EXPECT_STREQ(a->status._buffer[0].values._buffer[1].value, "can0 bus-off");
  dds_return_loan(r.reader, samples, n);
}

TEST(Dds, PublishingAllocatesNothingOfOurs) {
  auto pub = DdsPublisher::create(options("/aprt/test_pose3"));
  ASSERT_TRUE(pub) << pub.error().message();
  const DdsPose p = make_pose();
  ASSERT_TRUE(pub.value()->publish_pose(p));  // first write: Cyclone's lazy set-up
  AllocationScope scope;
  for (int i = 0; i < 50; ++i) ASSERT_TRUE(pub.value()->publish_pose(p));
  if (allocation_counter_covers_malloc()) {
    // Without a sanitizer malloc is counted too, and Cyclone (C) serialises
    // each sample into a buffer it mallocs: only C++ allocations are ours.
    GTEST_SKIP() << "malloc counted (Cyclone's own serdata): " << scope.count()
                 << " over 50 writes";
  }
  EXPECT_EQ(scope.count(), 0u);
}

TEST(Dds, BadTopicIsAClearError) {
  DdsOptions o = options("/bad topic name!");
  auto pub = DdsPublisher::create(o);
  ASSERT_FALSE(pub);
  EXPECT_NE(std::string(pub.error().message()).find("dds:"), std::string::npos);
}

// The start-up wait (dds_discovery.h): bounded, over as soon as every other
// participant has told an endpoint, and honest about one that never does.
TEST(Dds, StartUpWaitsForTheEndpointsOfParticipantsAlreadyThere) {
  const uint32_t domain = test_domain();
  const std::string xml = dds_loopback_config(domain);
  // Loopback only, like the publisher's; made already when an earlier test of this process did.
  const dds_entity_t d = dds_create_domain(domain, xml.c_str());
  ASSERT_TRUE(d > 0 || d == DDS_RETCODE_PRECONDITION_NOT_MET) << d;
  DdsOptions o = options("/aprt_test/discovery_pose");
  o.domain = domain;
  o.discovery_wait_ms = 3000;
  {  // nobody else: the quiet period (100 ms) only
    auto pub = DdsPublisher::create(o);
    ASSERT_TRUE(pub) << pub.error().message();
    const DdsDiscoveryReport& r = pub.value()->discovery();
    EXPECT_EQ(r.participants, 0);
    EXPECT_EQ(r.pending, 0);
    EXPECT_GE(r.waited_ns, 100000000);
    EXPECT_LT(r.waited_ns, 2000000000);
  }
  // A participant with a reader: known, its endpoint known, no full wait.
  const dds_entity_t peer = dds_create_participant(domain, nullptr, nullptr);
  const dds_entity_t t =
      dds_create_topic(peer, &geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc,
                       "rt/aprt_test/discovery_pose", nullptr, nullptr);
  ASSERT_GT(dds_create_reader(peer, t, nullptr, nullptr), 0);
  {
    auto pub = DdsPublisher::create(o);
    ASSERT_TRUE(pub) << pub.error().message();
    const DdsDiscoveryReport& r = pub.value()->discovery();
    EXPECT_EQ(r.participants, 1);
    EXPECT_EQ(r.pending, 0);
    EXPECT_LT(r.waited_ns, 2000000000);
  }
  // A participant that never tells an endpoint: the wait ends at its bound, saying so.
  const dds_entity_t bare = dds_create_participant(domain, nullptr, nullptr);
  o.discovery_wait_ms = 300;
  {
    auto pub = DdsPublisher::create(o);
    ASSERT_TRUE(pub) << pub.error().message();
    const DdsDiscoveryReport& r = pub.value()->discovery();
    EXPECT_EQ(r.participants, 2);
    EXPECT_EQ(r.pending, 1);
    EXPECT_GE(r.waited_ns, 300000000);
  }
  o.discovery_wait_ms = 0;  // off: no wait at all
  {
    auto pub = DdsPublisher::create(o);
    ASSERT_TRUE(pub) << pub.error().message();
    EXPECT_EQ(pub.value()->discovery().waited_ns, 0);
  }
  dds_delete(bare);
  dds_delete(peer);
  if (d > 0) dds_delete(d);
}

// A ROS 2 LiDAR driver's side: PointCloud2 with x y z intensity float32 and
// a ring field, 20-byte points (scan `k`: `n` points at x = k, y = i).
struct CloudWriter {
  dds_entity_t participant = 0, writer = 0;
  explicit CloudWriter(const char* topic) {
    participant = dds_create_participant(test_domain(), nullptr, nullptr);
    const dds_entity_t t = dds_create_topic(participant, &sensor_msgs_msg_dds__PointCloud2__desc,
                                            topic, nullptr, nullptr);
    dds_qos_t* q = dds_create_qos();
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 5);
    writer = dds_create_writer(participant, t, q, nullptr);
    dds_delete_qos(q);
  }
  ~CloudWriter() {
    if (participant > 0) dds_delete(participant);
  }
  void write(int k, uint32_t n, bool drop_z = false) {
    char x[] = "x", y[] = "y", z[] = "z", in[] = "intensity", ring[] = "ring", frame[] = "lidar";
    sensor_msgs_msg_dds__PointField_ f[5] = {
        {x, 0, 7, 1}, {y, 4, 7, 1}, {z, 8, 7, 1}, {in, 12, 7, 1}, {ring, 16, 4, 1}};
    std::vector<uint8_t> data(size_t(n) * 20, 0);
    for (uint32_t i = 0; i < n; ++i) {
      const float v[4] = {float(k), float(i), 0.5f, 3.0f};
      std::memcpy(&data[size_t(i) * 20], v, sizeof v);
    }
    sensor_msgs_msg_dds__PointCloud2_ m{};
    m.header.stamp.sec = 1795000000 + k;
    m.header.frame_id = frame;
    m.height = 1;
    m.width = n;
    m.fields._buffer = drop_z ? f + 3 : f;
    m.fields._length = m.fields._maximum = drop_z ? 2 : 5;
    m.point_step = 20;
    m.row_step = 20 * n;
    m.data._buffer = data.data();
    m.data._length = m.data._maximum = uint32_t(data.size());
    m.is_dense = true;
    ASSERT_GE(dds_write(writer, &m), 0);
  }
};

TEST(Dds, PointCloud2ArrivesDecodedNewestFirst) {
  PointCloud2Options o;
  o.domain = test_domain();
  o.loopback_only = true;
  o.topic = "/aprt_test/points";
  o.reliable = true;  // the test must not lose samples; the default is best effort
  auto reader = PointCloud2Reader::create(o);
  ASSERT_TRUE(reader) << reader.error().message();
  EXPECT_STREQ(PointCloud2Reader::type_name(), "sensor_msgs::msg::dds_::PointCloud2_");
  CloudWriter w("rt/aprt_test/points");
  for (int i = 0; i < 500 && (*reader)->publishers() == 0; ++i) usleep(10000);
  ASSERT_EQ((*reader)->publishers(), 1);
  auto cloud = std::move(PointCloud::create(1000).value());
  int64_t stamp = 0;
  EXPECT_FALSE((*reader)->take_latest(PointRegion{}, cloud.get(), 1000000, &stamp));
  w.write(1, 300);
  ASSERT_TRUE((*reader)->take_latest(PointRegion{}, cloud.get(), 2000000000, &stamp));
  EXPECT_EQ(cloud->size(), 300u);
  EXPECT_EQ(cloud->points()[150].y, 150.0f);
  EXPECT_EQ(cloud->points()[299].y, 200.0f);  // through the gate: clipped to the region
  EXPECT_EQ(cloud->stats().clipped, 99u);
  EXPECT_EQ(cloud->points()[0].intensity, 3.0f);
  EXPECT_EQ(stamp, int64_t(1795000001) * 1000000000);
  // Three waiting: the newest is decoded, the two before it superseded.
  w.write(2, 10);
  w.write(3, 20);
  w.write(4, 30);
  usleep(200000);
  ASSERT_TRUE((*reader)->take_latest(PointRegion{}, cloud.get(), 2000000000, &stamp));
  EXPECT_EQ(cloud->size(), 30u);
  EXPECT_EQ(cloud->points()[0].x, 4.0f);
  EXPECT_EQ((*reader)->stats().superseded, 2u);
  // A cloud without z: refused with its reason, the last good scan kept.
  w.write(5, 40, true);
  EXPECT_FALSE((*reader)->take_latest(PointRegion{}, cloud.get(), 2000000000, &stamp));
  EXPECT_EQ(cloud->size(), 30u);
  EXPECT_EQ((*reader)->stats().refused[size_t(CloudRefusal::kMissingField)], 1u);
  EXPECT_NE(std::strstr((*reader)->stats().last_refusal, "no 'x' field"), nullptr)
      << (*reader)->stats().last_refusal;
  EXPECT_EQ((*reader)->stats().decoded, 2u);
}

// A vehicle's side: geometry_msgs/TwistWithCovarianceStamped as Autoware's
// vehicle_velocity_converter publishes it.
struct TwistWriter {
  dds_entity_t participant = 0, writer = 0;
  explicit TwistWriter(const char* topic) {
    participant = dds_create_participant(test_domain(), nullptr, nullptr);
    const dds_entity_t t =
        dds_create_topic(participant, &geometry_msgs_msg_dds__TwistWithCovarianceStamped__desc,
                         topic, nullptr, nullptr);
    dds_qos_t* q = dds_create_qos();
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 200);
    writer = dds_create_writer(participant, t, q, nullptr);
    dds_delete_qos(q);
  }
  ~TwistWriter() {
    if (participant > 0) dds_delete(participant);
  }
  void write(int64_t stamp_ns, double v, double w) {
    char frame[] = "base_link";
    geometry_msgs_msg_dds__TwistWithCovarianceStamped_ m{};
    m.header.stamp.sec = int32_t(stamp_ns / 1000000000);
    m.header.stamp.nanosec = uint32_t(stamp_ns % 1000000000);
    m.header.frame_id = frame;
    m.twist.twist.linear.x = v;
    m.twist.twist.angular.z = w;
    ASSERT_GE(dds_write(writer, &m), 0);
  }
};

TEST(Dds, TwistsArriveAndNonsenseIsRefused) {
  TwistOptions o;
  o.domain = test_domain();
  o.loopback_only = true;
  o.topic = "/aprt_test/twist";
  auto reader = TwistReader::create(o);
  ASSERT_TRUE(reader) << reader.error().message();
  TwistWriter w("rt/aprt_test/twist");
  for (int i = 0; i < 500 && (*reader)->publishers() == 0; ++i) usleep(10000);
  ASSERT_EQ((*reader)->publishers(), 1);
  w.write(1795000000123456789, 12.5, -0.25);
  w.write(1795000000133456789, std::nan(""), 0);  // refused
  w.write(1795000000143456789, 12.6, 45.0 * 3);   // a yaw rate in degrees: refused
  w.write(1795000000153456789, 12.7, -0.2);
  TwistSample got[8];
  int n = 0;
  for (int i = 0; i < 100 && n < 2; ++i) n += (*reader)->take(got + n, 8 - n, 20000000);
  ASSERT_EQ(n, 2);
  EXPECT_EQ(got[0].stamp_ns, 1795000000123456789);
  EXPECT_EQ(got[0].speed_mps, 12.5);
  EXPECT_EQ(got[0].yaw_rate_radps, -0.25);
  EXPECT_EQ(got[1].speed_mps, 12.7);
  EXPECT_EQ((*reader)->stats().received, 2u);
  EXPECT_EQ((*reader)->stats().refused, 2u);
  EXPECT_STREQ(TwistReader::type_name(), "geometry_msgs::msg::dds_::TwistWithCovarianceStamped_");
}

// The loop's side: the odometry thread queues the twists, the reading at a
// frame's time integrates them; asking allocates nothing.
TEST(Dds, OdometryInputGivesTheMotionBetweenTwoFrames) {
  Config::Odometry c;
  c.source = "dds";
  c.domain = int(test_domain());
  c.loopback_only = true;
  c.topic = "/aprt_test/odometry";
  c.depth = 200;  // the test writes a second's twists at once
  auto in = OdometryInput::create(c);
  ASSERT_TRUE(in) << in.error().message();
  TwistWriter w("rt/aprt_test/odometry");
  for (int i = 0; i < 500 && (*in)->publishers() == 0; ++i) usleep(10000);
  ASSERT_EQ((*in)->publishers(), 1);
  const int64_t t0 = 1795000000000000000;
  for (int k = 0; k < 100; ++k) w.write(t0 + int64_t(k) * 10000000, 10.0, 0.1);  // 100 Hz, 1 s
  for (int i = 0; i < 300 && (*in)->received() < 100; ++i) usleep(10000);
  ASSERT_EQ((*in)->received(), 100u);
  usleep(50000);  // the last batch into the queue
  const AllocationScope scope;
  const OdometryReading a = (*in)->reading_at(t0 + 200000000);
  const OdometryReading b = (*in)->reading_at(t0 + 700000000);
  EXPECT_EQ(scope.count(), 0u);
  PlanarMotion m;
  ASSERT_TRUE(motion_between(a, b, &m));
  EXPECT_NEAR(m.distance_m, 5.0, 1e-6);
  EXPECT_NEAR(m.dyaw, 0.05, 1e-9);
  EXPECT_NEAR(m.dx, 100.0 * std::sin(0.05), 1e-6);         // an arc of radius v / w = 100 m
  EXPECT_FALSE((*in)->reading_at(t0 + 2000000000).valid);  // the bus silent since 1 s
  EXPECT_EQ((*in)->dropped(), 0u);
}

// The estimator with the filter on the live odometry (odometry.source dds):
// estimates along a straight road at 10 m/s, frames stamped on the twists'
// clock; the filter starts, and the pose that goes out is valid and on the road.
TEST(Dds, TheFilterRunsOnLiveOdometry) {
  auto cfg = parse_config(
      "model: m\nsource: {type: v4l2}\nodometry: {source: dds, topic: /aprt_test/live, "
      "loopback_only: true, depth: 500, domain: " +
          std::to_string(test_domain()) + "}\nsanity: {filter: {enabled: true, confirm: 3}}\n",
      "test.yaml");
  ASSERT_TRUE(cfg) << cfg.error().message();
  auto in = OdometryInput::create(cfg->odometry);
  ASSERT_TRUE(in) << in.error().message();
  TwistWriter w("rt/aprt_test/live");
  for (int i = 0; i < 500 && (*in)->publishers() == 0; ++i) usleep(10000);
  ASSERT_EQ((*in)->publishers(), 1);
  const int64_t t0 = 1795000000000000000;
  for (int k = 0; k < 300; ++k) w.write(t0 + int64_t(k) * 10000000, 10.0, 0.0);  // 3 s at 100 Hz
  for (int i = 0; i < 300 && (*in)->received() < 300; ++i) usleep(10000);
  ASSERT_EQ((*in)->received(), 300u);
  usleep(50000);
  Estimator est(cfg.value(), ModelMeta{}, nullptr, 0);
  est.use_odometry(in->get());
  uint32_t flags = 0;
  for (int k = 0; k < 60; ++k) {  // 25 Hz frames over 2.4 s
    PoseRecord rec;
    rec.source_stamp_ns = t0 + int64_t(k) * 40000000;
    const double truth = 100.0 + 10.0 * 0.04 * k;
    rec.pose.position[0] = truth + (k % 2 ? 1.0 : -1.0);  // an estimate a metre off
    rec.pose.position[1] = 50.0;
    rec.pose.has_sigma = true;
    rec.pose.sigma_position_m[0] = rec.pose.sigma_position_m[1] = 1.0;
    rec.pose.sigma_position_m[2] = 0.5;
    rec.pose.sigma_rotation_rad[0] = rec.pose.sigma_rotation_rad[1] = 0.01;
    rec.pose.sigma_rotation_rad[2] = 0.01;
    rec.inference_start_ns = rec.inference_end_ns = 1;
    flags = est.check(&rec, 0);
    if (k >= 20) {
      EXPECT_EQ(flags, 0u) << k;
      EXPECT_TRUE(rec.filter.fix);
      EXPECT_NEAR(rec.pose.position[0], truth, 0.6) << k;  // the two-metre zigzag averaged out
    }
  }
}

}  // namespace
}  // namespace aprt
