// A ROS 2 peer on Fast DDS (eProsima; ROS 2's default middleware), built
// from the ROS 2 message definitions (msg/ -> msg2idl.py -> fastddsgen), not
// from aprt's IDL: what aprt meets in a car when the other nodes run
// rmw_fastrtps. Two jobs, each run by tests/peers/fastdds_check.py:
//
//   fastdds_peer listen [--domain N] [--loopback] [--pose-topic T]
//                       [--diagnostics-topic T] [--timeout S] [--ready FILE]
//     subscribes like a ROS 2 node with default QoS (reliable, keep last 10,
//     volatile) and prints each pose, in `aprt ddsdump`'s format, and each
//     diagnostics message in full; exits on SIGTERM/SIGINT or after S s.
//
//   fastdds_peer clouds --scans DIR [--count N] [--rate HZ] [--domain N]
//                       [--loopback] [--topic T] [--pose-topic T]
//                       [--stamp-sec S] [--timeout S]
//     publishes KITTI .bin scans of DIR (sorted) as sensor_msgs/PointCloud2
//     (x y z intensity float32) with stamps S+i . 123456789 and prints every
//     pose received back ("pose STAMP") and every cloud sent ("cloud STAMP").
//
// --loopback: UDP on 127.0.0.1 only, discovery by unicast to 127.0.0.1 (what
// aprt's output.dds.loopback_only does); without it, Fast DDS's defaults.
// Test code, not aprt's: plain C++ with exceptions and allocation allowed.
#include <dirent.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <fstream>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "ros2_msgs.h"
#include "ros2_msgsPubSubTypes.h"

namespace fdds = eprosima::fastdds::dds;
using eprosima::fastrtps::rtps::IPLocator;
using eprosima::fastrtps::rtps::Locator_t;

namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) {
  g_stop = true;
}

struct Options {
  std::string mode;
  uint32_t domain = 0;
  bool loopback = false;
  std::string pose_topic = "/aprt/pose_with_covariance";
  std::string diagnostics_topic = "/diagnostics";
  std::string cloud_topic = "/points_raw";
  std::string scans;
  std::string ready;
  int count = 0;
  double rate = 10;
  double timeout = 30;
  int32_t stamp_sec = 1000;
};

[[noreturn]] void usage(const char* why) {
  std::fprintf(stderr,
               "fastdds_peer: %s\nusage: fastdds_peer listen|clouds [--domain N] [--loopback] "
               "[--pose-topic T] [--diagnostics-topic T] [--topic T] [--scans DIR] [--count N] "
               "[--rate HZ] [--stamp-sec S] [--timeout S] [--ready FILE]\n",
               why);
  std::exit(2);
}

Options parse(int argc, char** argv) {
  Options o;
  if (argc < 2) usage("no job given");
  o.mode = argv[1];
  if (o.mode != "listen" && o.mode != "clouds") usage("the job is listen or clouds");
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage((a + " needs a value").c_str());
      return argv[++i];
    };
    if (a == "--domain")
      o.domain = uint32_t(std::stoul(value()));
    else if (a == "--loopback")
      o.loopback = true;
    else if (a == "--pose-topic")
      o.pose_topic = value();
    else if (a == "--diagnostics-topic")
      o.diagnostics_topic = value();
    else if (a == "--topic")
      o.cloud_topic = value();
    else if (a == "--scans")
      o.scans = value();
    else if (a == "--count")
      o.count = std::stoi(value());
    else if (a == "--rate")
      o.rate = std::stod(value());
    else if (a == "--timeout")
      o.timeout = std::stod(value());
    else if (a == "--stamp-sec")
      o.stamp_sec = std::stoi(value());
    else if (a == "--ready")
      o.ready = value();
    else
      usage(("unknown argument " + a).c_str());
  }
  return o;
}

// ROS 2's topic mangling: "/x/y" -> "rt/x/y".
std::string dds_topic(const std::string& ros) {
  return "rt" + (ros.empty() || ros[0] != '/' ? "/" + ros : ros);
}

fdds::DomainParticipant* join(const Options& o) {
  fdds::DomainParticipantQos q = fdds::PARTICIPANT_QOS_DEFAULT;
  q.name("fastdds_peer");
  if (o.loopback) {
    auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
    udp->interfaceWhiteList.push_back("127.0.0.1");
    q.transport().user_transports.push_back(udp);
    q.transport().use_builtin_transports = false;
    Locator_t peer;
    IPLocator::setIPv4(peer, 127, 0, 0, 1);
    q.wire_protocol().builtin.initialPeersList.push_back(peer);
  }
  auto* p = fdds::DomainParticipantFactory::get_instance()->create_participant(o.domain, q);
  if (!p) {
    std::fprintf(stderr, "fastdds_peer: cannot create a participant on domain %u\n", o.domain);
    std::exit(1);
  }
  return p;
}

fdds::Topic* topic(fdds::DomainParticipant* p, fdds::TypeSupport& type, const std::string& ros) {
  if (type.register_type(p) != ReturnCode_t::RETCODE_OK) {
    std::fprintf(stderr, "fastdds_peer: cannot register %s\n", type.get_type_name().c_str());
    std::exit(1);
  }
  auto* t = p->create_topic(dds_topic(ros), type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  if (!t) {
    std::fprintf(stderr, "fastdds_peer: cannot create topic %s\n", dds_topic(ros).c_str());
    std::exit(1);
  }
  return t;
}

// ROS 2's default QoS profile for subscriptions: reliable, keep last 10, volatile.
fdds::DataReaderQos ros_default_reader() {
  fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
  q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
  q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = 10;
  q.durability().kind = fdds::VOLATILE_DURABILITY_QOS;
  return q;
}

std::mutex g_print;

class PoseListener : public fdds::DataReaderListener {
 public:
  explicit PoseListener(bool stamp_only) : stamp_only_(stamp_only) {}
  void on_data_available(fdds::DataReader* reader) override {
    geometry_msgs::msg::dds_::PoseWithCovarianceStamped_ m;
    fdds::SampleInfo info;
    while (reader->take_next_sample(&m, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      const auto& h = m.header();
      const auto& pose = m.pose().pose();
      const auto& c = m.pose().covariance();
      std::lock_guard<std::mutex> lock(g_print);
      if (stamp_only_) {
        std::printf("pose %d.%09u\n", h.stamp().sec(), h.stamp().nanosec());
      } else {
        // `aprt ddsdump`'s line, so the two decoders' outputs compare as text.
        std::printf("%d.%09u %s %.4f %.4f %.4f %.6f %.6f %.6f %.6f sigma_xy %.3f\n",
                    h.stamp().sec(), h.stamp().nanosec(), h.frame_id().c_str(), pose.position().x(),
                    pose.position().y(), pose.position().z(), pose.orientation().w(),
                    pose.orientation().x(), pose.orientation().y(), pose.orientation().z(),
                    std::sqrt(c[0] > 0 ? c[0] : 0));
      }
      std::fflush(stdout);
    }
  }

 private:
  bool stamp_only_;
};

class DiagnosticsListener : public fdds::DataReaderListener {
 public:
  void on_data_available(fdds::DataReader* reader) override {
    diagnostic_msgs::msg::dds_::DiagnosticArray_ m;
    fdds::SampleInfo info;
    while (reader->take_next_sample(&m, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      std::lock_guard<std::mutex> lock(g_print);
      for (const auto& s : m.status()) {
        std::printf("status %d.%09u level %u name %s hardware_id %s message %s |",
                    m.header().stamp().sec(), m.header().stamp().nanosec(), unsigned(s.level()),
                    s.name().c_str(), s.hardware_id().c_str(), s.message().c_str());
        for (const auto& kv : s.values())
          std::printf(" %s=%s", kv.key().c_str(), kv.value().c_str());
        std::printf("\n");
      }
      std::fflush(stdout);
    }
  }
};

void touch(const std::string& path) {
  if (path.empty()) return;
  std::ofstream(path) << "ready\n";
}

void wait_until(std::chrono::steady_clock::time_point end) {
  while (!g_stop && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

int listen(const Options& o) {
  auto* p = join(o);
  fdds::TypeSupport pose_type(new geometry_msgs::msg::dds_::PoseWithCovarianceStamped_PubSubType());
  fdds::TypeSupport diag_type(new diagnostic_msgs::msg::dds_::DiagnosticArray_PubSubType());
  auto* tp = topic(p, pose_type, o.pose_topic);
  auto* td = topic(p, diag_type, o.diagnostics_topic);
  auto* sub = p->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  PoseListener poses(false);
  DiagnosticsListener diagnostics;
  auto* rp = sub->create_datareader(tp, ros_default_reader(), &poses);
  auto* rd = sub->create_datareader(td, ros_default_reader(), &diagnostics);
  if (!rp || !rd) {
    std::fprintf(stderr, "fastdds_peer: cannot create the readers\n");
    return 1;
  }
  std::fprintf(stderr, "fastdds_peer: listening on domain %u, %s and %s%s\n", o.domain,
               dds_topic(o.pose_topic).c_str(), dds_topic(o.diagnostics_topic).c_str(),
               o.loopback ? " (loopback)" : "");
  touch(o.ready);
  wait_until(std::chrono::steady_clock::now() +
             std::chrono::milliseconds(int64_t(o.timeout * 1000)));
  p->delete_contained_entities();
  fdds::DomainParticipantFactory::get_instance()->delete_participant(p);
  return 0;
}

std::vector<std::string> scan_files(const std::string& dir) {
  std::vector<std::string> files;
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      const std::string n = e->d_name;
      if (n.size() > 4 && n.compare(n.size() - 4, 4, ".bin") == 0) files.push_back(dir + "/" + n);
    }
    closedir(d);
  }
  std::sort(files.begin(), files.end());
  return files;
}

int clouds(const Options& o) {
  const auto files = scan_files(o.scans);
  if (files.empty()) {
    std::fprintf(stderr, "fastdds_peer: no .bin scans in %s\n", o.scans.c_str());
    return 1;
  }
  auto* p = join(o);
  fdds::TypeSupport cloud_type(new sensor_msgs::msg::dds_::PointCloud2_PubSubType());
  fdds::TypeSupport pose_type(new geometry_msgs::msg::dds_::PoseWithCovarianceStamped_PubSubType());
  auto* tc = topic(p, cloud_type, o.cloud_topic);
  auto* tp = topic(p, pose_type, o.pose_topic);
  PoseListener poses(true);
  auto* reader = p->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT)
                     ->create_datareader(tp, ros_default_reader(), &poses);
  // ROS 2's sensor-data profile: best effort, keep last 5.
  fdds::DataWriterQos wq = fdds::DATAWRITER_QOS_DEFAULT;
  wq.reliability().kind = fdds::BEST_EFFORT_RELIABILITY_QOS;
  wq.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
  wq.history().depth = 5;
  auto* writer = p->create_publisher(fdds::PUBLISHER_QOS_DEFAULT)->create_datawriter(tc, wq);
  if (!reader || !writer) {
    std::fprintf(stderr, "fastdds_peer: cannot create the endpoints\n");
    return 1;
  }
  // Wait (bounded) until aprt's cloud reader and pose writer have both
  // matched ours, so no cloud goes to nobody and no pose is lost to discovery.
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::milliseconds(int64_t(o.timeout * 1000));
  fdds::PublicationMatchedStatus matched;
  fdds::SubscriptionMatchedStatus heard;
  while (!g_stop && std::chrono::steady_clock::now() < deadline) {
    writer->get_publication_matched_status(matched);
    reader->get_subscription_matched_status(heard);
    if (matched.current_count > 0 && heard.current_count > 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (matched.current_count == 0 || heard.current_count == 0) {
    std::fprintf(stderr, "fastdds_peer: %s within %.0f s\n",
                 matched.current_count == 0 ? "no reader of the clouds matched"
                                            : "no writer of the poses matched",
                 o.timeout);
    return 1;
  }
  const int n = o.count > 0 ? o.count : int(files.size());
  const auto period = std::chrono::microseconds(int64_t(1e6 / (o.rate > 0 ? o.rate : 10)));
  auto next = std::chrono::steady_clock::now();
  for (int i = 0; i < n && !g_stop; ++i) {
    std::ifstream f(files[size_t(i) % files.size()], std::ios::binary);
    std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(f)),
                               std::istreambuf_iterator<char>());
    sensor_msgs::msg::dds_::PointCloud2_ m;
    m.header().stamp().sec(o.stamp_sec + i);
    m.header().stamp().nanosec(123456789);
    m.header().frame_id("lidar");
    std::vector<sensor_msgs::msg::dds_::PointField_> fields(4);
    const char* names[4] = {"x", "y", "z", "intensity"};
    for (uint32_t k = 0; k < 4; ++k) {
      fields[k].name(names[k]);
      fields[k].offset(4 * k);
      fields[k].datatype(7);  // PointField_Constants::FLOAT32
      fields[k].count(1);
    }
    m.fields(fields);
    m.height(1);
    m.point_step(16);
    m.width(uint32_t(bytes.size() / 16));
    m.row_step(m.width() * 16);
    bytes.resize(size_t(m.row_step()));
    m.data(bytes);
    m.is_bigendian(false);
    m.is_dense(true);
    writer->write(&m);
    {
      std::lock_guard<std::mutex> lock(g_print);
      std::printf("cloud %d.%09u %u points\n", o.stamp_sec + i, 123456789u, m.width());
      std::fflush(stdout);
    }
    next += period;
    std::this_thread::sleep_until(next);
  }
  // The last poses come back after the last cloud: give them a moment.
  wait_until(std::chrono::steady_clock::now() + std::chrono::seconds(2));
  p->delete_contained_entities();
  fdds::DomainParticipantFactory::get_instance()->delete_participant(p);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGINT, on_signal);
  return o.mode == "listen" ? listen(o) : clouds(o);
}
