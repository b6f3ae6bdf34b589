// A procedural town for training and testing pose regression: a street grid
// with a roundabout, buildings with distinctive facades, landmarks, street
// lights and trees, all from one seed. Map frame: x east, y north, z up,
// metres; the town spans [0, extent] in x and y.
#pragma once

#include <cstdint>
#include <vector>

namespace aprt::synth {

struct Vec3 {
  double x = 0, y = 0, z = 0;
};

inline Vec3 operator+(Vec3 a, Vec3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline Vec3 operator-(Vec3 a, Vec3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Vec3 operator*(Vec3 a, double s) {
  return {a.x * s, a.y * s, a.z * s};
}
inline double dot(Vec3 a, Vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

struct Color {
  float r = 0, g = 0, b = 0;
};

enum class Material : uint8_t {
  kFacade,     // windows grid on a base colour (params: base, window, floor height, columns)
  kStriped,    // horizontal bands (params: base, second colour)
  kPlain,      // uniform colour
  kBillboard,  // bold checker pattern
};

// Axis-aligned box resting on the ground (or raised, z0 > 0).
struct Box {
  double x0, y0, z0, x1, y1, z1;
  Material material;
  Color base, second;
  double floor_h = 3.0, window_w = 2.5;
  uint32_t id;
};

// Vertical cylinder (poles, trunks, the tower, the roundabout monument).
struct Cylinder {
  double cx, cy, r, z0, z1;
  Color color;
  uint32_t id;
};

struct Sphere {
  double cx, cy, cz, r;
  Color color;
  uint32_t id;
  bool lamp = false;  // a street light's head: it glows when the lamps are on (night)
};

struct Town {
  double extent = 200.0;   // metres
  double block = 50.0;     // street spacing
  double road_half = 5.0;  // half road width
  double sidewalk = 2.0;
  double roundabout_r = 13.0;  // outer radius of the ring road
  double island_r = 7.0;
  Vec3 roundabout;               // centre
  int park_bx = 0, park_by = 0;  // the block that is a park
  std::vector<Box> boxes;
  std::vector<Cylinder> cylinders;
  std::vector<Sphere> spheres;

  int streets() const { return int(extent / block) + 1; }
  // Ground colour at (x, y): road, lane marking, sidewalk, grass.
  Color ground(double x, double y) const;
  // Distance from (x, y) to the nearest street centre line (roads only).
  bool on_road(double x, double y) const;
};

Town make_town(uint32_t seed);

}  // namespace aprt::synth
