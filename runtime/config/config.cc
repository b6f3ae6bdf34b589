#include "runtime/config/config.h"

#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>

#include "runtime/base/file_io.h"
#include "runtime/config/config_reader.h"
#include "runtime/config/yaml_tree.h"

namespace aprt {

namespace {
constexpr struct {
  const char* name;
  SourceType type;
} kSourceTypes[] = {
    {"replay", SourceType::kReplay},           {"v4l2", SourceType::kV4l2},
    {"libcamera", SourceType::kLibcamera},     {"lidar_replay", SourceType::kLidarReplay},
    {"pointcloud2", SourceType::kPointCloud2}, {"mcap", SourceType::kMcap},
};
}  // namespace

const char* source_type_name(SourceType t) {
  for (const auto& n : kSourceTypes) {
    if (n.type == t) return n.name;
  }
  return "?";
}

bool source_type_from_name(const std::string& name, SourceType* out) {
  for (const auto& n : kSourceTypes) {
    if (name == n.name) {
      *out = n.type;
      return true;
    }
  }
  return false;
}
namespace {

using config::Reader;

// CPUs this machine has (thread and worker pinning refer to them).
int configured_cpus() {
  const long n = sysconf(_SC_NPROCESSORS_CONF);
  return n > 0 ? int(n) : 1;
}
using yaml::Node;

Status read_transform(Reader& r, const Node* parent, const char* name, double xyz[3],
                      double rpy[3]) {
  const std::string path = std::string("extrinsics.") + name;
  const Node* n = parent ? parent->get(name) : nullptr;
  Status s;
  if (!(s = r.map(n, path, {"xyz", "rpy_deg"}))) return s;
  if (!(s = r.vec3(n, path, "xyz", -1e7, 1e7, xyz))) return s;
  return r.vec3(n, path, "rpy_deg", -360, 360, rpy);
}

Status read_source(Reader& r, const Node* src, const std::string& path, Config::Source* src_out) {
  Status s;
  const auto join = [&](const std::string& p, const char* k) { return Reader::join(p, k); };
#define TRY(expr) \
  if (!(s = (expr))) return s
  TRY(r.map(src, path, {"type", "replay", "v4l2", "libcamera", "pointcloud2", "lidar", "mcap"}));
  std::string type = source_type_name(src_out->type);
  TRY(r.str(src, path, "type", &type,
            {"replay", "v4l2", "libcamera", "lidar_replay", "pointcloud2", "mcap"}));
  source_type_from_name(type, &src_out->type);  // one of the choices just checked
  const Node* rp = src ? src->get("replay") : nullptr;
  TRY(r.map(rp, join(path, "replay"), {"path", "rate_hz", "loop", "frames"}));
  TRY(r.str(rp, join(path, "replay"), "path", &src_out->replay.path));
  if (rp && rp->get("rate_hz") && rp->get("rate_hz")->scalar == "recorded") {
    src_out->replay.recorded = true;
  } else {
    TRY(r.num(rp, join(path, "replay"), "rate_hz", 0, 1000, &src_out->replay.rate_hz));
  }
  TRY(r.boolean(rp, join(path, "replay"), "loop", &src_out->replay.loop));
  TRY(r.integer(rp, join(path, "replay"), "frames", 0, 1000000000, &src_out->replay.frames));
  const Node* mc = src ? src->get("mcap") : nullptr;
  TRY(r.map(mc, join(path, "mcap"), {"topic"}));
  TRY(r.str(mc, join(path, "mcap"), "topic", &src_out->mcap.topic));
  const Node* v = src ? src->get("v4l2") : nullptr;
  TRY(r.map(v, join(path, "v4l2"),
            {"device", "width", "height", "format", "fps", "buffers", "frames"}));
  TRY(r.str(v, join(path, "v4l2"), "device", &src_out->v4l2.device));
  TRY(r.integer(v, join(path, "v4l2"), "width", 16, 8192, &src_out->v4l2.width));
  TRY(r.integer(v, join(path, "v4l2"), "height", 16, 8192, &src_out->v4l2.height));
  TRY(r.str(v, join(path, "v4l2"), "format", &src_out->v4l2.format,
            {"YUYV", "UYVY", "NV12", "RGB24", "BGR24", "MJPEG"}));
  TRY(r.integer(v, join(path, "v4l2"), "fps", 1, 1000, &src_out->v4l2.fps));
  TRY(r.integer(v, join(path, "v4l2"), "buffers", 2, 32, &src_out->v4l2.buffers));
  TRY(r.integer(v, join(path, "v4l2"), "frames", 0, 1000000000, &src_out->v4l2.frames));
  const Node* lc = src ? src->get("libcamera") : nullptr;
  const std::string lp = join(path, "libcamera");
  TRY(r.map(lc, lp, {"camera", "width", "height", "format", "role", "fps", "buffers", "frames"}));
  TRY(r.integer(lc, lp, "fps", 1, 1000, &src_out->libcamera.fps));
  TRY(r.str(lc, lp, "camera", &src_out->libcamera.camera));
  TRY(r.integer(lc, lp, "width", 16, 8192, &src_out->libcamera.width));
  TRY(r.integer(lc, lp, "height", 16, 8192, &src_out->libcamera.height));
  TRY(r.str(lc, lp, "format", &src_out->libcamera.format,
            {"YUYV", "UYVY", "NV12", "RGB24", "BGR24", "MJPEG"}));
  TRY(r.str(lc, lp, "role", &src_out->libcamera.role, {"viewfinder", "video", "still"}));
  TRY(r.integer(lc, lp, "buffers", 2, 32, &src_out->libcamera.buffers));
  TRY(r.integer(lc, lp, "frames", 0, 1000000000, &src_out->libcamera.frames));
  const Node* pc = src ? src->get("pointcloud2") : nullptr;
  const std::string pp = join(path, "pointcloud2");
  TRY(r.map(pc, pp, {"topic", "domain", "reliable", "depth", "loopback_only", "frames"}));
  TRY(r.str(pc, pp, "topic", &src_out->pointcloud2.topic));
  TRY(r.integer(pc, pp, "domain", 0, 232, &src_out->pointcloud2.domain));
  TRY(r.boolean(pc, pp, "reliable", &src_out->pointcloud2.reliable));
  TRY(r.integer(pc, pp, "depth", 1, 100, &src_out->pointcloud2.depth));
  TRY(r.boolean(pc, pp, "loopback_only", &src_out->pointcloud2.loopback_only));
  TRY(r.integer(pc, pp, "frames", 0, 1000000000, &src_out->pointcloud2.frames));
  const Node* li = src ? src->get("lidar") : nullptr;
  const std::string lip = join(path, "lidar");
  TRY(r.map(li, lip, {"max_points", "region", "min_points"}));
  TRY(r.integer(li, lip, "max_points", 1, 1 << 22, &src_out->lidar.max_points));
  TRY(r.integer(li, lip, "min_points", 0, 1 << 22, &src_out->lidar.min_points));
  const Node* rg = li ? li->get("region") : nullptr;
  const std::string rgp = join(lip, "region");
  TRY(r.map(rg, rgp, {"x_min", "x_max", "y_min", "y_max", "z_min", "z_max"}));
  static const char* const kRegion[6] = {"x_min", "x_max", "y_min", "y_max", "z_min", "z_max"};
  for (int k = 0; k < 6; ++k) {
    TRY(r.num(rg, rgp, kRegion[k], -1e5, 1e5, &src_out->lidar.region[k]));
  }
  for (int k = 0; k < 6; k += 2) {
    if (!(src_out->lidar.region[k] < src_out->lidar.region[k + 1])) {
      return r.fail(rg, rgp, "every axis needs min < max");
    }
  }

#undef TRY
  return ok();
}

// cameras: a list of {name, source, sensor_to_base_link}; not beside `source`
// or `extrinsics.sensor_to_base_link`, which describe the single camera.
Status read_cameras(Reader& r, const Node* root, Config* c) {
  const Node* list = root->get("cameras");
  if (!list || list->kind == Node::kNull) return ok();
  if (list->kind != Node::kSeq || list->seq.empty()) {
    return r.fail(list, "cameras", "expected a list of cameras");
  }
  if (list->seq.size() > size_t(Config::kMaxCameras)) {
    return r.fail(list, "cameras", "at most " + std::to_string(Config::kMaxCameras) + " cameras");
  }
  if (const Node* s = root->get("source")) {
    return r.fail(s, "source", "give either `source` (one camera) or `cameras`, not both");
  }
  const Node* ex = root->get("extrinsics");
  if (const Node* e = ex ? ex->get("sensor_to_base_link") : nullptr) {
    return r.fail(e, "extrinsics.sensor_to_base_link",
                  "with `cameras`, each camera has its own sensor_to_base_link");
  }
  Status s;
  for (size_t i = 0; i < list->seq.size(); ++i) {
    const Node* n = list->seq[i].get();
    const std::string p = "cameras[" + std::to_string(i) + "]";
    if (n->kind != Node::kMap) return r.fail(n, p, "expected a mapping");
    if (!(s = r.map(n, p, {"name", "source", "sensor_to_base_link"}))) return s;
    Config::Camera cam;
    if (!(s = r.str(n, p, "name", &cam.name))) return s;
    if (cam.name.empty())
      return r.fail(n, p + ".name", "required (it names the camera in diagnostics)");
    for (const Config::Camera& other : c->cameras) {
      if (other.name == cam.name)
        return r.fail(n->get("name"), p + ".name", "'" + cam.name + "' is used twice");
    }
    const Node* src = n->get("source");
    if (!src) return r.fail(n, p + ".source", "required");
    if (!(s = read_source(r, src, p + ".source", &cam.source))) return s;
    if (cam.source.replay_source() && cam.source.replay.path.empty()) {
      return r.fail(src, p + ".source.replay.path", "required for a replay source");
    }
    const Node* t = n->get("sensor_to_base_link");
    const std::string tp = p + ".sensor_to_base_link";
    if (!(s = r.map(t, tp, {"xyz", "rpy_deg"}))) return s;
    if (!(s = r.vec3(t, tp, "xyz", -1e7, 1e7, cam.sensor_xyz))) return s;
    if (!(s = r.vec3(t, tp, "rpy_deg", -360, 360, cam.sensor_rpy_deg))) return s;
    c->cameras.push_back(cam);
  }
  c->source = c->cameras[0].source;
  for (int k = 0; k < 3; ++k) {
    c->extrinsics.sensor_xyz[k] = c->cameras[0].sensor_xyz[k];
    c->extrinsics.sensor_rpy_deg[k] = c->cameras[0].sensor_rpy_deg[k];
  }
  return ok();
}

Status read_thread(Reader& r, const Node* root, const char* name, ThreadConfig* t) {
  const std::string path = std::string("threads.") + name;
  const Node* n = root ? root->get(name) : nullptr;
  Status s;
  if (!(s = r.map(n, path, {"priority", "cpu"}))) return s;
  if (!(s = r.integer(n, path, "priority", 0, 99, &t->priority))) return s;
  return r.integer(n, path, "cpu", -1, long(configured_cpus()) - 1, &t->cpu);
}

}  // namespace

Expected<Config> parse_config(const std::string& text, const std::string& origin) {
  auto tree = yaml::parse(text, origin);
  if (!tree) return tree.error();
  const Node* root = tree->get();
  Reader r(origin);
  Config c;
  c.origin = origin;
  Status s;
#define APRT_TRY(expr) \
  if (!(s = (expr))) return s.error()
  APRT_TRY(r.map(root, "",
                 {"model", "model_signing", "engine", "source", "cameras", "fusion", "output",
                  "extrinsics", "supervisor", "sanity", "odometry", "threads", "fault_injection"}));
  if (root && root->kind == Node::kMap) {
    APRT_TRY(r.str(root, "", "model", &c.model));
    if (const Node* fi = root->get("fault_injection"); fi && fi->kind != Node::kNull) {
      if (fi->kind != Node::kSeq) return r.fail(fi, "fault_injection", "expected a list of faults");
      if (fi->seq.size() > size_t(kMaxFaults)) {
        return r.fail(fi, "fault_injection", "at most " + std::to_string(kMaxFaults) + " faults");
      }
      for (size_t i = 0; i < fi->seq.size(); ++i) {
        const Node* f = fi->seq[i].get();
        const std::string p = "fault_injection[" + std::to_string(i) + "]";
        if (f->kind != Node::kMap) return r.fail(f, p, "expected a mapping");
        APRT_TRY(r.map(f, p, {"fault", "at_frame", "count", "duration_ms"}));
        std::string name;
        APRT_TRY(r.str(f, p, "fault", &name,
                       {"camera_stall", "inference_overrun", "nan_output", "publish_failure",
                        "inference_hang"}));
        FaultSpec spec;
        if (!fault_kind_from_name(name, &spec.kind)) return r.fail(f, p + ".fault", "required");
        int at = 0, count = 1;
        APRT_TRY(r.integer(f, p, "at_frame", 0, 100000000, &at));
        APRT_TRY(r.integer(f, p, "count", 1, 100000000, &count));
        APRT_TRY(r.num(f, p, "duration_ms", 0, 600000, &spec.duration_ms));
        spec.at_frame = uint64_t(at);
        spec.count = uint64_t(count);
        const bool timed = spec.kind == FaultKind::kCameraStall ||
                           spec.kind == FaultKind::kInferenceOverrun ||
                           spec.kind == FaultKind::kInferenceHang;
        if (timed && spec.duration_ms <= 0) {
          return r.fail(f, p + ".duration_ms", "required (> 0) for " + name);
        }
        c.fault_injection.push_back(spec);
      }
    }
    const Node* ms = root->get("model_signing");
    APRT_TRY(r.map(ms, "model_signing", {"public_key", "required"}));
    APRT_TRY(r.str(ms, "model_signing", "public_key", &c.model_signing.public_key));
    APRT_TRY(r.boolean(ms, "model_signing", "required", &c.model_signing.required));
    const Node* e = root->get("engine");
    APRT_TRY(r.map(e, "engine", {"threads", "isa", "cpus"}));
    APRT_TRY(r.integer(e, "engine", "threads", 1, 16, &c.engine.threads));
    APRT_TRY(r.str(e, "engine", "isa", &c.engine.isa, {"auto", "ref", "avx512", "avx2", "neon"}));
    APRT_TRY(r.int_list(e, "engine", "cpus", 0, long(configured_cpus()) - 1, &c.engine.cpus));

    APRT_TRY(read_source(r, root->get("source"), "source", &c.source));
    APRT_TRY(read_cameras(r, root, &c));
    const Node* fu = root->get("fusion");
    APRT_TRY(r.map(
        fu, "fusion",
        {"max_position_spread_m", "max_orientation_spread_deg", "min_agreeing", "max_frame_skew_ms",
         "companion", "companion_max_age_ms", "min_lead_s", "cross_check"}));
    APRT_TRY(
        r.num(fu, "fusion", "max_position_spread_m", 0.01, 1e4, &c.fusion.max_position_spread_m));
    APRT_TRY(r.num(fu, "fusion", "max_orientation_spread_deg", 0.01, 180,
                   &c.fusion.max_orientation_spread_deg));
    APRT_TRY(
        r.integer(fu, "fusion", "min_agreeing", 1, Config::kMaxCameras, &c.fusion.min_agreeing));
    APRT_TRY(r.num(fu, "fusion", "max_frame_skew_ms", 0, 1000, &c.fusion.max_frame_skew_ms));
    APRT_TRY(r.str(fu, "fusion", "companion", &c.fusion.companion));
    APRT_TRY(r.num(fu, "fusion", "companion_max_age_ms", 1, 10000, &c.fusion.companion_max_age_ms));
    APRT_TRY(r.num(fu, "fusion", "min_lead_s", 0, 3600, &c.fusion.min_lead_s));
    APRT_TRY(r.boolean(fu, "fusion", "cross_check", &c.fusion.cross_check));

    const Node* out = root->get("output");
    APRT_TRY(r.map(out, "output",
                   {"console", "summary", "frame_id", "sigma_position_m", "sigma_orientation_deg",
                    "status_rate_hz", "records", "dds", "can"}));
    APRT_TRY(r.boolean(out, "output", "console", &c.output.console));
    APRT_TRY(r.boolean(out, "output", "summary", &c.output.summary));
    APRT_TRY(r.str(out, "output", "frame_id", &c.output.frame_id, {}, /*non_empty=*/true));
    APRT_TRY(r.num(out, "output", "sigma_position_m", 0, 600, &c.output.sigma_position_m));
    APRT_TRY(r.num(out, "output", "sigma_orientation_deg", 0, 25, &c.output.sigma_orientation_deg));
    APRT_TRY(r.num(out, "output", "status_rate_hz", 0.1, 100, &c.output.status_rate_hz));
    APRT_TRY(r.integer(out, "output", "records", 1024, 1 << 24, &c.output.records));
    const Node* dds = out ? out->get("dds") : nullptr;
    APRT_TRY(r.map(dds, "output.dds",
                   {"enabled", "domain", "pose_topic", "diagnostics_topic", "reliability", "depth",
                    "loopback_only", "discovery_wait_ms"}));
    APRT_TRY(r.boolean(dds, "output.dds", "enabled", &c.output.dds.enabled));
    APRT_TRY(r.integer(dds, "output.dds", "domain", 0, 232, &c.output.dds.domain));
    APRT_TRY(r.str(dds, "output.dds", "pose_topic", &c.output.dds.pose_topic));
    APRT_TRY(r.str(dds, "output.dds", "diagnostics_topic", &c.output.dds.diagnostics_topic));
    APRT_TRY(r.str(dds, "output.dds", "reliability", &c.output.dds.reliability,
                   {"reliable", "best_effort"}));
    APRT_TRY(r.integer(dds, "output.dds", "depth", 1, 1000, &c.output.dds.depth));
    APRT_TRY(r.boolean(dds, "output.dds", "loopback_only", &c.output.dds.loopback_only));
    APRT_TRY(r.integer(dds, "output.dds", "discovery_wait_ms", 0, 10000,
                       &c.output.dds.discovery_wait_ms));
    const Node* can = out ? out->get("can") : nullptr;
    APRT_TRY(
        r.map(can, "output.can", {"enabled", "interface", "fd", "cycle_ms", "recover_ms", "ids"}));
    APRT_TRY(r.boolean(can, "output.can", "enabled", &c.output.can.enabled));
    APRT_TRY(r.str(can, "output.can", "interface", &c.output.can.interface));
    APRT_TRY(r.boolean(can, "output.can", "fd", &c.output.can.fd));
    APRT_TRY(r.num(can, "output.can", "cycle_ms", 0, 60000, &c.output.can.cycle_ms));
    APRT_TRY(r.num(can, "output.can", "recover_ms", 10, 60000, &c.output.can.recover_ms));
    const Node* ids = can ? can->get("ids") : nullptr;
    static const char* const kIdNames[6] = {"status", "pos_xy", "pos_zqw", "quat_yz", "time", "fd"};
    APRT_TRY(
        r.map(ids, "output.can.ids", {"status", "pos_xy", "pos_zqw", "quat_yz", "time", "fd"}));
    for (int i = 0; i < 6; ++i) {
      APRT_TRY(r.id(ids, "output.can.ids", kIdNames[i], 0, 0x7FF, &c.output.can.ids[i]));
    }
    for (int i = 0; i < 6; ++i) {
      for (int j = 0; j < i; ++j) {
        if (c.output.can.ids[i] == c.output.can.ids[j]) {
          return Error(Errc::kInvalidArgument, "%s: output.can.ids: %s and %s share id 0x%x",
                       origin.c_str(), kIdNames[j], kIdNames[i], c.output.can.ids[i]);
        }
      }
    }

    const Node* ex = root->get("extrinsics");
    APRT_TRY(r.map(ex, "extrinsics", {"sensor_to_base_link", "map_offset"}));
    APRT_TRY(read_transform(r, ex, "sensor_to_base_link", c.extrinsics.sensor_xyz,
                            c.extrinsics.sensor_rpy_deg));
    APRT_TRY(read_transform(r, ex, "map_offset", c.extrinsics.map_offset_xyz,
                            c.extrinsics.map_offset_rpy_deg));

    const Node* sv = root->get("supervisor");
    APRT_TRY(r.map(sv, "supervisor",
                   {"rate_hz", "frame_timeout_ms", "inference_deadline_ms", "fault_after_s",
                    "watchdog_device", "watchdog_timeout_s", "systemd"}));
    APRT_TRY(r.num(sv, "supervisor", "rate_hz", 1, 1000, &c.supervisor.rate_hz));
    APRT_TRY(r.num(sv, "supervisor", "frame_timeout_ms", 1, 60000, &c.supervisor.frame_timeout_ms));
    APRT_TRY(r.num(sv, "supervisor", "inference_deadline_ms", 1, 60000,
                   &c.supervisor.inference_deadline_ms));
    APRT_TRY(r.num(sv, "supervisor", "fault_after_s", 0.1, 3600, &c.supervisor.fault_after_s));
    APRT_TRY(r.str(sv, "supervisor", "watchdog_device", &c.supervisor.watchdog_device));
    APRT_TRY(r.integer(sv, "supervisor", "watchdog_timeout_s", 1, 600,
                       &c.supervisor.watchdog_timeout_s));
    APRT_TRY(r.boolean(sv, "supervisor", "systemd", &c.supervisor.systemd));

    const Node* sa = root->get("sanity");
    APRT_TRY(
        r.map(sa, "sanity", {"bounds_margin", "max_jump_m", "max_speed_mps", "track", "filter"}));
    APRT_TRY(r.num(sa, "sanity", "bounds_margin", 0, 10, &c.sanity.bounds_margin));
    APRT_TRY(r.num(sa, "sanity", "max_jump_m", 0, 1e6, &c.sanity.max_jump_m));
    APRT_TRY(r.num(sa, "sanity", "max_speed_mps", 0, 1000, &c.sanity.max_speed_mps));
    const Node* tr = sa ? sa->get("track") : nullptr;
    const char* tp = "sanity.track";
    Config::Sanity::Track& t = c.sanity.track;
    APRT_TRY(r.map(tr, tp,
                   {"enabled", "max_radius_m", "max_yaw_deg", "gate_m", "gate_deg",
                    "gate_growth_mps", "confirm", "lost_after"}));
    APRT_TRY(r.boolean(tr, tp, "enabled", &t.enabled));
    APRT_TRY(r.num(tr, tp, "max_radius_m", 0.1, 1e4, &t.max_radius_m));
    APRT_TRY(r.num(tr, tp, "max_yaw_deg", 0.1, 180, &t.max_yaw_deg));
    APRT_TRY(r.num(tr, tp, "gate_m", 0.1, 1e4, &t.gate_m));
    APRT_TRY(r.num(tr, tp, "gate_deg", 0.1, 180, &t.gate_deg));
    APRT_TRY(r.num(tr, tp, "gate_growth_mps", 0, 1000, &t.gate_growth_mps));
    APRT_TRY(r.integer(tr, tp, "confirm", 1, 1000, &t.confirm));
    APRT_TRY(r.integer(tr, tp, "lost_after", 1, 100000, &t.lost_after));
    const Node* fl = sa ? sa->get("filter") : nullptr;
    const char* fp = "sanity.filter";
    Config::Sanity::Filter& f = c.sanity.filter;
    APRT_TRY(r.map(
        fl, fp,
        {"enabled", "distance_noise", "yaw_noise_deg_per_m", "yaw_rate_noise_dps", "gate_chi2",
         "confirm", "take_over_after", "max_radius_m", "max_yaw_deg", "lost_radius_m",
         "position_sigma_scale", "estimate_max_radius_m", "estimate_max_yaw_deg",
         "estimate_sigma_scale", "disagreement_frames", "place_sigma_m", "place_length_m"}));
    APRT_TRY(r.boolean(fl, fp, "enabled", &f.enabled));
    APRT_TRY(r.num(fl, fp, "distance_noise", 0, 1, &f.distance_noise));
    APRT_TRY(r.num(fl, fp, "yaw_noise_deg_per_m", 0, 90, &f.yaw_noise_deg_per_m));
    APRT_TRY(r.num(fl, fp, "yaw_rate_noise_dps", 0, 90, &f.yaw_rate_noise_dps));
    APRT_TRY(r.num(fl, fp, "gate_chi2", 0.1, 1000, &f.gate_chi2));
    APRT_TRY(r.integer(fl, fp, "confirm", 1, 1000, &f.confirm));
    APRT_TRY(r.integer(fl, fp, "take_over_after", 1, 100000, &f.take_over_after));
    APRT_TRY(r.num(fl, fp, "max_radius_m", 0.01, 1e4, &f.max_radius_m));
    APRT_TRY(r.num(fl, fp, "max_yaw_deg", 0.01, 180, &f.max_yaw_deg));
    APRT_TRY(r.num(fl, fp, "lost_radius_m", 0.1, 1e6, &f.lost_radius_m));
    APRT_TRY(r.num(fl, fp, "position_sigma_scale", 0.01, 100, &f.position_sigma_scale));
    APRT_TRY(r.num(fl, fp, "estimate_max_radius_m", 0.01, 1e4, &f.estimate_max_radius_m));
    APRT_TRY(r.num(fl, fp, "estimate_max_yaw_deg", 0.01, 180, &f.estimate_max_yaw_deg));
    APRT_TRY(r.num(fl, fp, "estimate_sigma_scale", 0.01, 100, &f.estimate_sigma_scale));
    APRT_TRY(r.integer(fl, fp, "disagreement_frames", 0, 100000, &f.disagreement_frames));
    APRT_TRY(r.num(fl, fp, "place_sigma_m", 0, 1000, &f.place_sigma_m));
    APRT_TRY(r.num(fl, fp, "place_length_m", 0.1, 1e5, &f.place_length_m));

    const Node* od = root->get("odometry");
    Config::Odometry& o = c.odometry;
    APRT_TRY(r.map(od, "odometry",
                   {"source", "topic", "domain", "reliable", "loopback_only", "depth", "can"}));
    APRT_TRY(r.str(od, "odometry", "source", &o.source));
    APRT_TRY(r.str(od, "odometry", "topic", &o.topic));
    APRT_TRY(r.integer(od, "odometry", "domain", 0, 232, &o.domain));
    APRT_TRY(r.boolean(od, "odometry", "reliable", &o.reliable));
    APRT_TRY(r.boolean(od, "odometry", "loopback_only", &o.loopback_only));
    APRT_TRY(r.integer(od, "odometry", "depth", 1, 1000, &o.depth));
    if (o.source != "replay" && o.source != "dds" && o.source != "can") {
      return Error(Errc::kInvalidArgument,
                   "%s: odometry.source: '%s' is not one of replay (a replayed drive's "
                   "odometry.txt), dds (a TwistWithCovarianceStamped topic), can (the vehicle's "
                   "speed and yaw-rate signals)",
                   origin.c_str(), o.source.c_str());
    }
    const Node* oc = od ? od->get("can") : nullptr;
    APRT_TRY(r.map(oc, "odometry.can",
                   {"interface", "dbc", "speed", "yaw_rate", "speed_unit", "yaw_rate_unit",
                    "yaw_rate_clockwise", "max_pair_age_ms", "direction", "reverse_values"}));
    APRT_TRY(r.str(oc, "odometry.can", "interface", &o.can.interface));
    APRT_TRY(r.str(oc, "odometry.can", "dbc", &o.can.dbc));
    APRT_TRY(r.str(oc, "odometry.can", "speed", &o.can.speed));
    APRT_TRY(r.str(oc, "odometry.can", "yaw_rate", &o.can.yaw_rate));
    APRT_TRY(r.str(oc, "odometry.can", "speed_unit", &o.can.speed_unit));
    APRT_TRY(r.str(oc, "odometry.can", "yaw_rate_unit", &o.can.yaw_rate_unit));
    APRT_TRY(r.boolean(oc, "odometry.can", "yaw_rate_clockwise", &o.can.yaw_rate_clockwise));
    APRT_TRY(r.integer(oc, "odometry.can", "max_pair_age_ms", 1, 10000, &o.can.max_pair_age_ms));
    APRT_TRY(r.str(oc, "odometry.can", "direction", &o.can.direction));
    APRT_TRY(r.int_list(oc, "odometry.can", "reverse_values", -(1L << 31), (1L << 31) - 1,
                        &o.can.reverse_values));
    if (o.source == "can") {
      for (const auto& [key, value] :
           {std::pair<const char*, const std::string*>{"dbc", &o.can.dbc},
            {"speed", &o.can.speed},
            {"yaw_rate", &o.can.yaw_rate}}) {
        if (value->empty()) {
          return Error(Errc::kInvalidArgument, "%s: odometry.source can needs odometry.can.%s (%s)",
                       origin.c_str(), key,
                       std::strcmp(key, "dbc") == 0 ? "the vehicle's DBC file"
                                                    : "MESSAGE.SIGNAL of the DBC that carries it");
        }
      }
    }

    const Node* th = root->get("threads");
    APRT_TRY(r.map(th, "threads",
                   {"capture", "inference", "publish", "supervisor", "lock_memory", "stack_kib"}));
    APRT_TRY(read_thread(r, th, "capture", &c.threads.capture));
    APRT_TRY(read_thread(r, th, "inference", &c.threads.inference));
    APRT_TRY(read_thread(r, th, "publish", &c.threads.publish));
    APRT_TRY(read_thread(r, th, "supervisor", &c.threads.supervisor));
    APRT_TRY(r.boolean(th, "threads", "lock_memory", &c.threads.lock_memory));
    APRT_TRY(r.integer(th, "threads", "stack_kib", 128, 65536, &c.threads.stack_kib));
  } else if (root && root->kind != Node::kNull) {
    return Error(Errc::kInvalidArgument, "%s:%d: the document must be a mapping", origin.c_str(),
                 root->line);
  }
#undef APRT_TRY
  if (c.model.empty()) {
    return Error(Errc::kInvalidArgument, "%s: 'model' (path of the .aprt file) is required",
                 origin.c_str());
  }
  if (c.model_signing.required && c.model_signing.public_key.empty()) {
    return Error(Errc::kInvalidArgument,
                 "%s: model_signing.required needs model_signing.public_key (the key file made "
                 "by `aprt sign keygen`)",
                 origin.c_str());
  }
  if (c.source.replay_source() && c.source.replay.path.empty()) {
    return Error(Errc::kInvalidArgument, "%s: source.replay.path is required for a %s source",
                 origin.c_str(), source_type_name(c.source.type));
  }
  if (c.sanity.filter.enabled) {
    // Only a camera replay with odometry.txt carries the vehicle's motion in
    // this version; anywhere else every pose would go out flagged.
    const Config::Source& trigger = c.cameras.empty() ? c.source : c.cameras[0].source;
    if (c.odometry.source == "replay" && trigger.type != SourceType::kReplay) {
      return Error(Errc::kInvalidArgument,
                   "%s: sanity.filter needs the vehicle's odometry: with odometry.source replay "
                   "only a replayed drive's odometry.txt gives it (source.type is %s); set "
                   "odometry.source: dds for the vehicle's twist topic or can for its bus "
                   "signals, or disable the filter",
                   origin.c_str(), source_type_name(trigger.type));
    }
    if (!c.fusion.companion.empty()) {
      return Error(Errc::kInvalidArgument,
                   "%s: sanity.filter with fusion.companion: the filter takes one sensor's "
                   "estimates; disable one of them",
                   origin.c_str());
    }
  }
  for (const Config::Camera& cam : c.cameras) {
    if (cam.source.lidar_source()) {
      return Error(Errc::kInvalidArgument,
                   "%s: cameras.%s: a LiDAR source (%s) is one sensor: give it as `source`, not "
                   "in `cameras`",
                   origin.c_str(), cam.name.c_str(), source_type_name(cam.source.type));
    }
  }
  return c;
}

std::vector<Config::Camera> camera_list(const Config& c) {
  if (!c.cameras.empty()) return c.cameras;
  Config::Camera one;
  one.name = "camera";
  one.source = c.source;
  for (int k = 0; k < 3; ++k) {
    one.sensor_xyz[k] = c.extrinsics.sensor_xyz[k];
    one.sensor_rpy_deg[k] = c.extrinsics.sensor_rpy_deg[k];
  }
  return {one};
}

Expected<Config> load_config(const std::string& path) {
  std::string text;  // a regular file of at most 1 MiB: /dev/zero or a FIFO is refused
  if (Status s = read_input_file(path.c_str(), yaml::kMaxConfigBytes, "config", &text); !s) {
    return s.error();
  }
  return parse_config(text, path);
}

}  // namespace aprt
