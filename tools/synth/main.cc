// aprt_synth: renders a drive through the procedural town.
//
//   aprt_synth --out DIR [--split train|test] [--town-seed N] [--route-seed N]
//              [--frames N] [--width 256 --height 192 --hfov 90]
//              [--lighting day|overcast|morning|noon|haze|dusk|night] [--lane-jitter M]
//              [--camera-mount X,Y,Z,PITCH_DEG] [--view-jitter LAT,HEIGHT,PITCH,YAW]
//              [--threads N] [--lidar] [--beams 32] [--azimuths 1024]
//              [--lidar-range 80] [--lidar-noise 0.02] [--lidar-mount X,Y,Z]
//
// `aprt_synth --help` lists every option with its default.
//
// Writes the DeepLoc layout: DIR/poses.txt ("name x y z qw qx qy qz", the
// camera's pose in the map frame), DIR/images/NNNNNN.png, with --lidar
// DIR/lidar/NNNNNN.bin (KITTI: x y z intensity float32, sensor frame) and
// DIR/lidar_poses.txt, and DIR/dataset.json (intrinsics, mounting, lighting,
// seeds). Deterministic for given arguments.
#include <png.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include "tools/synth/drive.h"
#include "tools/synth/lighting.h"
#include "tools/synth/options.h"
#include "tools/synth/raycast.h"
#include "tools/synth/town.h"

namespace aprt::synth {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Quat {
  double w, x, y, z;
};

// Rotation R = Rz(yaw) * Ry(pitch) (pitch > 0 tilts the x axis down) as a quaternion.
Quat yaw_pitch(double yaw, double pitch) {
  const double cz = std::cos(yaw / 2), sz = std::sin(yaw / 2);
  const double cy = std::cos(pitch / 2), sy = std::sin(pitch / 2);
  return {cz * cy, -sz * sy, cz * sy, sz * cy};  // (0,0,sz,cz) * (0,sy,0,cy)
}

// Rotate v by quaternion q.
Vec3 rotate(Quat q, Vec3 v) {
  const double w = q.w, x = q.x, y = q.y, z = q.z;
  const double r00 = 1 - 2 * (y * y + z * z), r01 = 2 * (x * y - w * z), r02 = 2 * (x * z + w * y);
  const double r10 = 2 * (x * y + w * z), r11 = 1 - 2 * (x * x + z * z), r12 = 2 * (y * z - w * x);
  const double r20 = 2 * (x * z - w * y), r21 = 2 * (y * z + w * x), r22 = 1 - 2 * (x * x + y * y);
  return {r00 * v.x + r01 * v.y + r02 * v.z, r10 * v.x + r11 * v.y + r12 * v.z,
          r20 * v.x + r21 * v.y + r22 * v.z};
}

bool write_png(const std::string& path, int w, int h, const std::vector<uint8_t>& rgb) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return false;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(f);
    return false;
  }
  png_init_io(png, f);
  png_set_IHDR(png, info, w, h, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < h; ++y) {
    png_write_row(png, const_cast<png_bytep>(rgb.data() + size_t(y) * w * 3));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return std::fclose(f) == 0;
}

uint8_t to_srgb(float v, double exposure) {
  const double x = std::clamp(v * exposure, 0.0, 1.0);
  return uint8_t(std::lround(255.0 * std::pow(x, 1.0 / 2.2)));
}

void render_image(const Scene& scene, const Options& o, const Lighting& L, Vec3 eye, Quat q,
                  std::vector<uint8_t>* rgb) {
  const double f = (o.width / 2.0) / std::tan(o.hfov_deg * kPi / 360.0);
  const double cx = o.width / 2.0 - 0.5, cy = o.height / 2.0 - 0.5;
  rgb->resize(size_t(o.width) * o.height * 3);
  for (int v = 0; v < o.height; ++v) {
    for (int u = 0; u < o.width; ++u) {
      Vec3 d{f, -(u - cx), -(v - cy)};  // camera body: x forward, y left, z up
      d = d * (1.0 / std::sqrt(dot(d, d)));
      const Color c = scene.shade(eye, rotate(q, d), L);
      uint8_t* p = rgb->data() + (size_t(v) * o.width + u) * 3;
      p[0] = to_srgb(c.r, L.exposure);
      p[1] = to_srgb(c.g, L.exposure);
      p[2] = to_srgb(c.b, L.exposure);
    }
  }
}

bool write_scan(const Scene& scene, const Options& o, Vec3 origin, double yaw, uint32_t seed,
                const std::string& path) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, o.lidar_noise);
  std::vector<float> pts;
  pts.reserve(size_t(o.beams) * o.azimuths * 4);
  const Quat q = yaw_pitch(yaw, 0.0);
  for (int b = 0; b < o.beams; ++b) {
    const double el = (-25.0 + 40.0 * b / std::max(1, o.beams - 1)) * kPi / 180;
    for (int a = 0; a < o.azimuths; ++a) {
      const double az = 2 * kPi * a / o.azimuths;
      const Vec3 local{std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
      Hit h;
      if (!scene.intersect(origin, rotate(q, local), o.lidar_range, &h) || h.t < 1.0) continue;
      const double r = h.t + noise(rng);
      const float lum = 0.3f * h.albedo.r + 0.6f * h.albedo.g + 0.1f * h.albedo.b;
      pts.insert(pts.end(), {float(local.x * r), float(local.y * r), float(local.z * r), lum});
    }
  }
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return false;
  const bool ok = std::fwrite(pts.data(), sizeof(float), pts.size(), f) == pts.size();
  return std::fclose(f) == 0 && ok;
}

// mkdir -p
bool make_dirs(const std::string& path) {
  for (size_t pos = 1; pos <= path.size(); ++pos) {
    if (pos != path.size() && path[pos] != '/') continue;
    const std::string part = path.substr(0, pos);
    if (mkdir(part.c_str(), 0755) != 0 && errno != EEXIST) return false;
  }
  return true;
}

int run(int argc, char** argv) {
  Options o;
  if (const int code = parse_options(argc, argv, &o); code >= 0) return code;
  const Town town = make_town(o.town_seed);
  const Scene scene(town);
  RouteOptions ro;
  ro.seed = o.route_seed;
  ro.cover_all = o.split == "train";
  ro.max_length = o.max_length;
  ro.spacing = o.spacing;
  ro.lane_jitter = o.lane_jitter >= 0 ? o.lane_jitter : (o.split == "train" ? 0.5 : 0.7);
  std::vector<VehiclePose> path = drive(town, ro);
  if (o.frames > 0 && size_t(o.frames) < path.size()) path.resize(size_t(o.frames));
  for (const std::string& dir : {o.out, o.out + "/images", o.out + "/lidar"}) {
    if (!o.lidar && dir == o.out + "/lidar") continue;
    if (!o.images && dir == o.out + "/images") continue;
    if (!make_dirs(dir)) {
      std::fprintf(stderr, "aprt_synth: cannot create %s: %s\n", dir.c_str(), std::strerror(errno));
      return 1;
    }
  }
  Lighting L = *lighting_preset(o.lighting);  // checked by parse_options
  if (o.sun_override) L.sun_dir = sun_direction(o.sun_azimuth_deg, o.sun_elevation_deg);
  const double pitch = o.cam_pitch_deg * kPi / 180;
  std::vector<std::string> lines(path.size()), lidar_lines(path.size());
  std::vector<int> failed(size_t(o.threads), 0);
  auto worker = [&](int t) {
    std::vector<uint8_t> rgb;
    char name[64];
    for (size_t k = size_t(t); k < path.size(); k += size_t(o.threads)) {
      const VehiclePose& route = path[k];
      const ViewJitter j = view_jitter(o, k);
      // The vehicle moved across its heading (left positive) and turned.
      const VehiclePose vp{route.x - std::sin(route.yaw) * j.lateral,
                           route.y + std::cos(route.yaw) * j.lateral, route.yaw + j.yaw};
      const Quat qv = yaw_pitch(vp.yaw, 0.0);
      const Vec3 base{vp.x, vp.y, 0.0};
      const Vec3 eye = base + rotate(qv, {o.cam_x, o.cam_y, o.cam_z + j.height});
      const Quat qc = yaw_pitch(vp.yaw, pitch + j.pitch);
      std::snprintf(name, sizeof name, "images/%06zu.png", k);
      if (o.images) {
        render_image(scene, o, L, eye, qc, &rgb);
        if (!write_png(o.out + "/" + name, o.width, o.height, rgb)) failed[size_t(t)]++;
      }
      char line[256];
      std::snprintf(line, sizeof line, "%s %.4f %.4f %.4f %.6f %.6f %.6f %.6f", name, eye.x, eye.y,
                    eye.z, qc.w, qc.x, qc.y, qc.z);
      lines[k] = line;
      if (o.lidar) {
        const Vec3 origin = base + rotate(qv, {o.lidar_x, o.lidar_y, o.lidar_z});
        std::snprintf(name, sizeof name, "lidar/%06zu.bin", k);
        if (!write_scan(scene, o, origin, vp.yaw, o.route_seed * 100003u + uint32_t(k),
                        o.out + "/" + name)) {
          failed[size_t(t)]++;
        }
        std::snprintf(line, sizeof line, "%s %.4f %.4f %.4f %.6f %.6f %.6f %.6f", name, origin.x,
                      origin.y, origin.z, qv.w, qv.x, qv.y, qv.z);
        lidar_lines[k] = line;
      }
      if (t == 0 && o.progress && (k / size_t(o.threads)) % 500 == 499) {
        std::fprintf(stderr, "aprt_synth: %zu / %zu frames\n", k + 1, path.size());
      }
    }
  };
  std::vector<std::thread> threads;
  for (int t = 0; t < o.threads; ++t) threads.emplace_back(worker, t);
  for (auto& th : threads) th.join();
  for (int f : failed) {
    if (f) {
      std::fprintf(stderr, "aprt_synth: %d files could not be written under %s\n", f,
                   o.out.c_str());
      return 1;
    }
  }
  FILE* p = std::fopen((o.out + "/poses.txt").c_str(), "w");
  if (!p) return 1;
  std::fprintf(p,
               "# name x y z qw qx qy qz (camera pose in the map frame: x east, y north, z up;\n"
               "# camera body axes x forward, y left, z up)\n");
  for (const auto& l : lines) std::fprintf(p, "%s\n", l.c_str());
  std::fclose(p);
  if (o.lidar) {
    FILE* lp = std::fopen((o.out + "/lidar_poses.txt").c_str(), "w");
    if (!lp) return 1;
    std::fprintf(lp, "# name x y z qw qx qy qz (LiDAR pose in the map frame)\n");
    for (const auto& l : lidar_lines) std::fprintf(lp, "%s\n", l.c_str());
    std::fclose(lp);
  }
  FILE* j = std::fopen((o.out + "/dataset.json").c_str(), "w");
  if (!j) return 1;
  // Every generation parameter: the drive can be made again from this file alone
  // (the "command" line repeats it as arguments).
  const double f = (o.width / 2.0) / std::tan(o.hfov_deg * kPi / 360.0);
  char maxlen[32];
  std::snprintf(maxlen, sizeof maxlen, o.max_length >= 1e9 ? "null" : "%.3f", o.max_length);
  // The sun as given (null: the preset's); the command repeats it only when given.
  char sun_json[48] = "null", sun_arg[48] = "";
  if (o.sun_override) {
    std::snprintf(sun_json, sizeof sun_json, "[%.4f, %.4f]", o.sun_azimuth_deg,
                  o.sun_elevation_deg);
    std::snprintf(sun_arg, sizeof sun_arg, " --sun %g,%g", o.sun_azimuth_deg, o.sun_elevation_deg);
  }
  std::fprintf(
      j,
      "{\"generator\": \"aprt_synth\", \"split\": \"%s\", \"lighting\": \"%s\", "
      "\"sun_deg\": %s, \"town_seed\": %u, \"route_seed\": %u, \"frames\": %zu,\n"
      " \"frames_limit\": %d, \"max_length_m\": %s, \"spacing_m\": %.4f,\n"
      " \"camera\": {\"width\": %d, \"height\": %d, \"fx\": %.4f, \"fy\": %.4f, "
      "\"cx\": %.2f, \"cy\": %.2f, \"hfov_deg\": %.4f},\n"
      " \"camera_to_base_link\": {\"xyz\": [%.4f, %.4f, %.4f], \"rpy_deg\": [0, %.4f, 0]},\n"
      " \"lidar_to_base_link\": {\"xyz\": [%.4f, %.4f, %.4f], \"rpy_deg\": [0, 0, 0]},\n"
      " \"view_jitter\": {\"lateral_m\": %.4f, \"height_m\": %.4f, \"pitch_deg\": %.4f, "
      "\"yaw_deg\": %.4f},\n"
      " \"town_extent_m\": %.1f, \"street_spacing_m\": %.1f, \"road_width_m\": %.1f,\n"
      " \"lane_jitter_m\": %.4f, \"lidar\": %s, \"images\": %s, \"beams\": %d,\n"
      " \"azimuths\": %d, \"lidar_range_m\": %.4f, \"lidar_noise_m\": %.4f,\n"
      " \"command\": \"aprt_synth --split %s --lighting %s%s --town-seed %u --route-seed %u "
      "--frames %d%s%s --spacing %g --lane-jitter %g --view-jitter %g,%g,%g,%g --width %d "
      "--height %d --hfov %g --camera-mount %g,%g,%g,%g%s%s --beams %d --azimuths %d "
      "--lidar-range %g --lidar-noise %g --lidar-mount %g,%g,%g\"}\n",
      o.split.c_str(), o.lighting.c_str(), sun_json, o.town_seed, o.route_seed, path.size(),
      o.frames, maxlen, o.spacing, o.width, o.height, f, f, o.width / 2.0 - 0.5,
      o.height / 2.0 - 0.5, o.hfov_deg, o.cam_x, o.cam_y, o.cam_z, o.cam_pitch_deg, o.lidar_x,
      o.lidar_y, o.lidar_z, o.jitter_lateral, o.jitter_height, o.jitter_pitch_deg, o.jitter_yaw_deg,
      town.extent, town.block, 2 * town.road_half, ro.lane_jitter, o.lidar ? "true" : "false",
      o.images ? "true" : "false", o.beams, o.azimuths, o.lidar_range, o.lidar_noise,
      o.split.c_str(), o.lighting.c_str(), sun_arg, o.town_seed, o.route_seed, o.frames,
      o.max_length >= 1e9 ? "" : " --max-length ", o.max_length >= 1e9 ? "" : maxlen, o.spacing,
      ro.lane_jitter, o.jitter_lateral, o.jitter_height, o.jitter_pitch_deg, o.jitter_yaw_deg,
      o.width, o.height, o.hfov_deg, o.cam_x, o.cam_y, o.cam_z, o.cam_pitch_deg,
      o.lidar ? " --lidar" : "", o.images ? "" : " --no-images", o.beams, o.azimuths, o.lidar_range,
      o.lidar_noise, o.lidar_x, o.lidar_y, o.lidar_z);
  std::fclose(j);
  std::printf("aprt_synth: %zu frames (%s, %s) -> %s\n", path.size(), o.split.c_str(),
              o.lighting.c_str(), o.out.c_str());
  return 0;
}

}  // namespace
}  // namespace aprt::synth

int main(int argc, char** argv) {
  return aprt::synth::run(argc, argv);
}
