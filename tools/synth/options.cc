#include "tools/synth/options.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <optional>
#include <random>
#include <type_traits>

#include "tools/synth/lighting.h"

namespace aprt::synth {
namespace {

int usage() {
  std::fprintf(stderr, "usage: aprt_synth --out DIR [options]   (aprt_synth --help lists them)\n");
  return 2;
}

int help() {
  const Options d;
  std::printf(
      "aprt_synth: renders a drive through the procedural town (DeepLoc layout).\n"
      "\n"
      "  --out DIR              where poses.txt, images/, dataset.json go (required)\n"
      "  --split train|test     train: a route over every street in both directions;\n"
      "                         test: a random drive (give --max-length) [%s]\n"
      "  --town-seed N          the town (every shipped drive uses town 1) [%u]\n"
      "  --route-seed N         the route's turns and lane weaving phase [%u]\n"
      "  --frames N             stop after N frames (0: the whole route) [%d]\n"
      "  --max-length M         stop after M metres of route [unbounded]\n"
      "  --spacing M            metres between frames [%.1f]\n"
      "  --lane-jitter M        slow lateral weaving in the lane [train 0.5, test 0.7]\n"
      "  --view-jitter L,H,P,Y  per-frame random view: lateral offset +-L m, camera height\n"
      "                         +-H m, pitch +-P deg, yaw +-Y deg [0,0,0,0]\n"
      "  --lighting NAME        %s [%s]\n"
      "  --sun AZ,EL            move the preset's sun: azimuth 0..360 deg from east,\n"
      "                         counter-clockwise; elevation 5..85 deg [the preset's]\n"
      "  --width W --height H --hfov DEG   the pinhole camera [%d x %d, %.0f deg]\n"
      "  --camera-mount X,Y,Z,PITCH_DEG    camera on base_link [%.2f,%.2f,%.2f,%.1f]\n"
      "  --lidar                also ray-cast LiDAR scans (KITTI .bin) of the same poses\n"
      "  --beams N --azimuths N --lidar-range M --lidar-noise M   [%d, %d, %.0f m, %.2f m]\n"
      "  --lidar-mount X,Y,Z    LiDAR on base_link [%.2f,%.2f,%.2f]\n"
      "  --no-images            with --lidar: the scans only, no camera images (poses.txt\n"
      "                         still says where the camera was); ~5x faster\n"
      "  --threads N            rendering threads [%d]\n"
      "  --quiet                no progress lines on stderr\n"
      "\n"
      "The shipped model's data (tools/synth/town_drives.sh, docs/evaluation.md):\n"
      "  training    route seeds 1-6, 8, 9 and 26-41 (split train) under day, overcast,\n"
      "              morning, noon (all but 1-4 with --view-jitter); seeds 42-49 under\n"
      "              day, morning, noon with the sun moved low (--sun)\n"
      "  validation  route seeds 11-19, 600 m, under all six daylight presets\n"
      "              (chooses; never trained on)\n"
      "  test        route seed 7, dusk, 600 m (data/demo_drive), and the unseen routes\n"
      "              21 (noon), 22 (dusk), 23 (haze), 24 (day, camera 0.25 m higher),\n"
      "              600 m: looked at once per model\n"
      "haze and dusk light no training drive.\n",
      d.split.c_str(), d.town_seed, d.route_seed, d.frames, d.spacing, kLightingNames,
      d.lighting.c_str(), d.width, d.height, d.hfov_deg, d.cam_x, d.cam_y, d.cam_z, d.cam_pitch_deg,
      d.beams, d.azimuths, d.lidar_range, d.lidar_noise, d.lidar_x, d.lidar_y, d.lidar_z,
      d.threads);
  return 0;
}

}  // namespace

ViewJitter view_jitter(const Options& o, size_t frame) {
  if (o.jitter_lateral == 0 && o.jitter_height == 0 && o.jitter_pitch_deg == 0 &&
      o.jitter_yaw_deg == 0) {
    return {};
  }
  std::mt19937 rng(o.route_seed * 2654435761u ^ uint32_t(frame * 40503u + 977u));
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  constexpr double kDeg = 3.14159265358979323846 / 180;
  ViewJitter j;
  j.lateral = o.jitter_lateral * u(rng);
  j.height = o.jitter_height * u(rng);
  j.pitch = o.jitter_pitch_deg * kDeg * u(rng);
  j.yaw = o.jitter_yaw_deg * kDeg * u(rng);
  return j;
}

int parse_options(int argc, char** argv, Options* out) {
  Options& o = *out;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    const char* v = nullptr;
    if (a == "--help" || a == "-h") return help();
    if (a == "--lidar") {
      o.lidar = true;
      continue;
    }
    if (a == "--no-images") {
      o.images = false;
      continue;
    }
    if (a == "--quiet") {
      o.progress = false;
      continue;
    }
    if (!(v = next())) return usage();
    // Numbers must parse whole: "--frames 1O" is refused, never read as 1.
    bool number_ok = true;
    std::string expected = "a valid number";
    auto real = [&](double* out) {
      char* end = nullptr;
      errno = 0;
      const double d = std::strtod(v, &end);
      number_ok = end != v && *end == '\0' && errno == 0 && std::isfinite(d);
      if (number_ok) *out = d;
    };
    // "a,b,c": exactly `count` numbers.
    auto reals = [&](std::initializer_list<double*> outs) {
      expected = std::to_string(outs.size()) + " comma-separated numbers";
      const char* p = v;
      for (double* out : outs) {
        char* end = nullptr;
        errno = 0;
        const double d = std::strtod(p, &end);
        number_ok = number_ok && end != p && errno == 0 && std::isfinite(d);
        if (!number_ok) return;
        *out = d;
        p = end;
        if (out != *(outs.end() - 1)) {
          number_ok = *p == ',';
          if (!number_ok) return;
          ++p;
        }
      }
      number_ok = *p == '\0';
    };
    auto integer = [&](auto* out) {
      double d = 0;
      real(&d);
      number_ok = number_ok && d == std::floor(d) && d >= 0 && d <= 4294967295.0;
      if (number_ok) *out = static_cast<std::remove_pointer_t<decltype(out)>>(d);
    };
    if (a == "--out")
      o.out = v;
    else if (a == "--split")
      o.split = v;
    else if (a == "--lighting")
      o.lighting = v;
    else if (a == "--town-seed")
      integer(&o.town_seed);
    else if (a == "--route-seed")
      integer(&o.route_seed);
    else if (a == "--frames")
      integer(&o.frames);
    else if (a == "--max-length")
      real(&o.max_length);
    else if (a == "--spacing")
      real(&o.spacing);
    else if (a == "--lane-jitter")
      real(&o.lane_jitter);
    else if (a == "--width")
      integer(&o.width);
    else if (a == "--height")
      integer(&o.height);
    else if (a == "--hfov")
      real(&o.hfov_deg);
    else if (a == "--beams")
      integer(&o.beams);
    else if (a == "--azimuths")
      integer(&o.azimuths);
    else if (a == "--lidar-range")
      real(&o.lidar_range);
    else if (a == "--lidar-noise")
      real(&o.lidar_noise);
    else if (a == "--camera-mount")
      reals({&o.cam_x, &o.cam_y, &o.cam_z, &o.cam_pitch_deg});
    else if (a == "--view-jitter")
      reals({&o.jitter_lateral, &o.jitter_height, &o.jitter_pitch_deg, &o.jitter_yaw_deg});
    else if (a == "--sun") {
      reals({&o.sun_azimuth_deg, &o.sun_elevation_deg});
      o.sun_override = true;
    } else if (a == "--lidar-mount")
      reals({&o.lidar_x, &o.lidar_y, &o.lidar_z});
    else if (a == "--threads")
      integer(&o.threads);
    else {
      std::fprintf(stderr, "aprt_synth: unknown option '%s'\n", a.c_str());
      return usage();
    }
    if (!number_ok) {
      std::fprintf(stderr, "aprt_synth: %s '%s' is not %s\n", a.c_str(), v, expected.c_str());
      return 2;
    }
  }
  o.threads = std::max(1, o.threads);
  if (o.out.empty() || o.width < 8 || o.height < 8 || o.spacing <= 0 || o.hfov_deg <= 0 ||
      o.hfov_deg >= 180 || o.beams < 1 || o.azimuths < 1 || o.lidar_range <= 1.0 ||
      o.lidar_noise < 0 || std::fabs(o.cam_pitch_deg) >= 90) {
    return usage();
  }
  if (!o.images && !o.lidar) {
    std::fprintf(stderr, "aprt_synth: --no-images without --lidar would render nothing\n");
    return 2;
  }
  const std::optional<Lighting> lighting = lighting_preset(o.lighting);
  if (!lighting) {
    std::fprintf(stderr, "aprt_synth: unknown lighting '%s' (one of %s)\n", o.lighting.c_str(),
                 kLightingNames);
    return 2;
  }
  if (o.split != "train" && o.split != "test") {
    std::fprintf(stderr,
                 "aprt_synth: unknown split '%s' (train: every street both ways; test: "
                 "a random drive)\n",
                 o.split.c_str());
    return 2;
  }
  if (o.jitter_lateral < 0 || o.jitter_lateral > 2.0 || o.jitter_height < 0 ||
      o.jitter_height > 1.0 || o.jitter_pitch_deg < 0 || o.jitter_pitch_deg > 20 ||
      o.jitter_yaw_deg < 0 || o.jitter_yaw_deg > 45) {
    std::fprintf(stderr,
                 "aprt_synth: --view-jitter %g,%g,%g,%g out of range (lateral 0..2 m keeps the "
                 "camera on the road, height 0..1 m, pitch 0..20 deg, yaw 0..45 deg)\n",
                 o.jitter_lateral, o.jitter_height, o.jitter_pitch_deg, o.jitter_yaw_deg);
    return 2;
  }
  if (o.sun_override && (o.sun_azimuth_deg < 0 || o.sun_azimuth_deg > 360 ||
                         o.sun_elevation_deg < 5 || o.sun_elevation_deg > 85)) {
    std::fprintf(stderr,
                 "aprt_synth: --sun %g,%g out of range (azimuth 0..360 deg, elevation 5..85 deg: "
                 "a sun at the horizon or overhead casts no shadow the presets lack)\n",
                 o.sun_azimuth_deg, o.sun_elevation_deg);
    return 2;
  }
  if (o.lane_jitter > 2.0) {
    std::fprintf(stderr, "aprt_synth: --lane-jitter %.2f m would leave the 2.5 m lane\n",
                 o.lane_jitter);
    return 2;
  }
  return -1;
}

}  // namespace aprt::synth
