// aprt ddsdump [--config FILE] [--domain N] [--topic NAME] [--loopback] [--timeout S] [--count N]
//
// The localisation stack's view of aprt's DDS output: subscribes to the pose
// (geometry_msgs/msg/PoseWithCovarianceStamped) and the diagnostics topic
// like a ROS 2 node with default QoS and prints every pose received, one
// line each, and the status changes. Exit 0 when at least one pose (or
// --count poses) arrived before the timeout, 1 otherwise.
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>

#include "drivers/output/dds/dds_listener.h"
#include "runtime/cli/args.h"
#include "runtime/cli/commands.h"
#include "runtime/config/config.h"

namespace aprt::cli {
namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) {
  g_stop = 1;
}

int64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

}  // namespace

int cmd_ddsdump(int argc, char** argv) {
  Args args(argc, argv);
  if (args.flag("--help")) {
    std::printf(
        "usage: aprt ddsdump [options]\n"
        "  --config FILE   take domain, topics, reliability and loopback from output.dds\n"
        "  --domain N      DDS domain (ROS_DOMAIN_ID), default 0\n"
        "  --topic NAME    ROS topic of the pose, default /aprt/pose_with_covariance\n"
        "  --loopback      discovery on 127.0.0.1 only (aprt's loopback_only profile)\n"
        "  --timeout S     stop after S seconds (default 10)\n"
        "  --count N       stop after N poses\n"
        "  --quiet         summary only\n");
    return 0;
  }
  const char* config = args.value("--config");
  const long domain = args.integer("--domain", -1, 0, 232);
  const char* topic = args.value("--topic");
  const bool loopback = args.flag("--loopback");
  const long timeout_s = args.integer("--timeout", 10, 1, 86400);
  const long count = args.integer("--count", 0, 1, 100000000);
  const bool quiet = args.flag("--quiet");
  if (args.refuse("ddsdump")) return 2;
  DdsOptions o;
  if (config) {
    auto c = load_config(config);
    if (!c) {
      std::fprintf(stderr, "aprt ddsdump: %s\n", c.error().message());
      return 2;
    }
    const Config::Output::Dds& d = c->output.dds;
    o.domain = uint32_t(d.domain);
    o.pose_topic = d.pose_topic;
    o.diagnostics_topic = d.diagnostics_topic;
    o.reliable = d.reliability == "reliable";
    o.loopback_only = d.loopback_only;
  }
  if (domain >= 0) o.domain = uint32_t(domain);
  if (topic) o.pose_topic = topic;
  if (loopback) o.loopback_only = true;
  auto listener = DdsListener::create(o);
  if (!listener) {
    std::fprintf(stderr, "aprt ddsdump: %s\n", listener.error().message());
    return 1;
  }
  DdsListener& l = *listener.value();
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::fprintf(stderr, "aprt ddsdump: domain %u, topic rt%s%s\n", o.domain,
               o.pose_topic[0] == '/' ? "" : "/", o.pose_topic.c_str());
  const int64_t end = now_ns() + int64_t(timeout_s) * 1000000000;
  long poses = 0, statuses = 0;
  char last_state[32] = "";
  DdsReceivedPose p[16];
  DdsReceivedStatus s[16];
  while (!g_stop && now_ns() < end && (count == 0 || poses < count)) {
    const int n = l.take_poses(p, 16, 100000000);
    for (int i = 0; i < n && (count == 0 || poses < count); ++i, ++poses) {
      if (quiet) continue;
      const double* c = p[i].covariance;
      std::printf("%lld.%09lld %s %.4f %.4f %.4f %.6f %.6f %.6f %.6f sigma_xy %.3f\n",
                  static_cast<long long>(p[i].stamp_ns / 1000000000),
                  static_cast<long long>(p[i].stamp_ns % 1000000000), p[i].frame_id,
                  p[i].position[0], p[i].position[1], p[i].position[2], p[i].orientation[0],
                  p[i].orientation[1], p[i].orientation[2], p[i].orientation[3],
                  std::sqrt(c[0] > 0 ? c[0] : 0));
    }
    const int m = l.take_status(s, 16);
    for (int i = 0; i < m; ++i, ++statuses) {
      if (std::strcmp(s[i].state, last_state) != 0) {
        std::snprintf(last_state, sizeof last_state, "%s", s[i].state);
        if (!quiet) std::printf("# status %s: %s\n", s[i].state, s[i].message);
      }
    }
    std::fflush(stdout);
  }
  std::printf("summary: %ld poses, %ld status messages, last state %s\n", poses, statuses,
              last_state[0] ? last_state : "(none)");
  return poses > 0 && (count == 0 || poses >= count) ? 0 : 1;
}

}  // namespace aprt::cli
