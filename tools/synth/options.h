// aprt_synth's options: their defaults, the parser (numbers must parse
// whole; ranges checked with a message), --help, and the per-frame view
// perturbation they describe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace aprt::synth {

struct Options {
  std::string out;
  std::string split = "train";
  std::string lighting = "day";
  // --sun AZ,EL: the lighting preset's colours with the sun moved to that
  // azimuth and elevation (degrees), so training can see shadows fall in
  // directions and lengths its presets do not have. Off: the preset's sun.
  bool sun_override = false;
  double sun_azimuth_deg = 0, sun_elevation_deg = 0;
  uint32_t town_seed = 1;
  uint32_t route_seed = 1;
  int frames = 0;  // 0: the whole route
  int width = 256, height = 192;
  double hfov_deg = 90.0;
  double spacing = 1.0;
  double max_length = 1e9;
  double lane_jitter = -1;  // < 0: the split's default
  bool lidar = false;
  bool images = true;  // false (--no-images): LiDAR scans only, 5x faster to render
  int beams = 32;
  int azimuths = 1024;
  double lidar_range = 80.0;
  double lidar_noise = 0.02;  // range noise, standard deviation in metres
  int threads = 2;
  // Mounting on base_link (x forward, y left, z up), metres and degrees.
  double cam_x = 1.2, cam_y = 0.0, cam_z = 1.55, cam_pitch_deg = 3.0;
  double lidar_x = 0.0, lidar_y = 0.0, lidar_z = 1.9;
  // Per-frame view perturbation (novel views around the route, LENS-style
  // coverage): each frame draws uniformly within +-these a lateral offset of
  // the vehicle across its heading (m), a camera height change (m), a camera
  // pitch change and a vehicle yaw change (degrees). 0: the route's own views.
  double jitter_lateral = 0, jitter_height = 0, jitter_pitch_deg = 0, jitter_yaw_deg = 0;
  bool progress = true;
};

// The frame's view perturbation, a pure function of the route seed and the
// frame index (the same arguments give the same files, whatever the threads).
struct ViewJitter {
  double lateral = 0, height = 0, pitch = 0, yaw = 0;  // m, m, rad, rad
};

ViewJitter view_jitter(const Options& o, size_t frame);

// Parses argv into *out. Returns -1 to go on, or the exit code to end with
// (0 after --help, 2 for a bad option, with the reason on stderr).
int parse_options(int argc, char** argv, Options* out);

}  // namespace aprt::synth
