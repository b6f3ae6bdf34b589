// Ray casting against the town: a 2-D grid over the ground plane lists the
// primitives in each cell; a ray walks the cells it crosses (DDA) and stops at
// the first hit that lies inside the cell being walked.
#pragma once

#include <vector>

#include "tools/synth/town.h"

namespace aprt::synth {

struct Hit {
  double t = 0;
  Vec3 point;
  Vec3 normal;
  Color albedo;
  bool sky = true;
  bool lamp = false;  // a street light's head
};

struct Lighting {
  Vec3 sun_dir{0.45, 0.45, 0.77};  // towards the sun, unit
  Color sun{1.0f, 0.97f, 0.9f};
  Color ambient{0.35f, 0.38f, 0.45f};
  Color sky_horizon{0.75f, 0.82f, 0.92f};
  Color sky_zenith{0.32f, 0.5f, 0.85f};
  Color fog{0.75f, 0.8f, 0.88f};
  double fog_distance = 600.0;  // e-folding distance of the haze, metres
  double exposure = 1.0;
  // Night: the street lights as point lights (intensity at 1 m, falling
  // with the square of the distance, reaching kLampReach) and the vehicle's
  // own headlights (a light at the camera, on what is below the horizon).
  double lamp_intensity = 0.0;
  Color lamp{1.0f, 0.82f, 0.55f};
  double headlight = 0.0;
};

class Scene {
 public:
  explicit Scene(const Town& town);
  bool intersect(Vec3 origin, Vec3 dir, double t_max, Hit* hit) const;
  // Shaded colour seen along a ray (hard shadows from the sun).
  Color shade(Vec3 origin, Vec3 dir, const Lighting& light) const;
  const Town& town() const { return town_; }

 private:
  struct Ref {
    int kind;  // 0 box, 1 cylinder, 2 sphere
    int index;
  };
  bool hit_cell(int cx, int cy, Vec3 o, Vec3 d, double t_min, double t_max, Hit* hit) const;
  // Light from the street lights and the headlights at a hit seen along d.
  Color night_light(const Hit& h, Vec3 d, const Lighting& L) const;
  Color surface(const Box& b, Vec3 p, Vec3 n) const;

  const Town& town_;
  double origin_ = -40.0;  // grid covers [origin_, origin_ + cells_ * cell_] in x and y
  double cell_ = 10.0;
  int cells_ = 0;
  std::vector<std::vector<Ref>> grid_;
  std::vector<std::vector<Vec3>> lamps_;  // street lights' heads per grid cell
};

}  // namespace aprt::synth
