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

#include <cstring>
#include <vector>

#include "drivers/dds/dds_domain.h"
#include "drivers/input/pointcloud2/pointcloud2_reader.h"
#include "drivers/output/dds/dds_publisher.h"
#include "ros2_interfaces.h"
#include "runtime/base/allocation_counter.h"

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

}  // namespace
}  // namespace aprt
