#include "tools/synth/raycast.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace aprt::synth {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kLampReach = 30.0;  // metres a street light is taken into account

double frac(double v) {
  return v - std::floor(v);
}

// Slab test; returns entry t (> t_min) and the face normal.
bool ray_box(const Box& b, Vec3 o, Vec3 d, double t_min, double* t_out, Vec3* n_out) {
  double t0 = t_min, t1 = kInf;
  Vec3 n{};
  const double lo[3] = {b.x0, b.y0, b.z0}, hi[3] = {b.x1, b.y1, b.z1};
  const double oo[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z};
  int axis = -1;
  double sign = 0;
  for (int a = 0; a < 3; ++a) {
    if (std::fabs(dd[a]) < 1e-12) {
      if (oo[a] < lo[a] || oo[a] > hi[a]) return false;
      continue;
    }
    double ta = (lo[a] - oo[a]) / dd[a], tb = (hi[a] - oo[a]) / dd[a];
    double s = -1;
    if (ta > tb) {
      std::swap(ta, tb);
      s = 1;
    }
    if (ta > t0) {
      t0 = ta;
      axis = a;
      sign = s;
    }
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  if (axis < 0) return false;  // origin inside the box
  if (axis == 0) n = {sign, 0, 0};
  if (axis == 1) n = {0, sign, 0};
  if (axis == 2) n = {0, 0, sign};
  *t_out = t0;
  *n_out = n;
  return true;
}

bool ray_cylinder(const Cylinder& c, Vec3 o, Vec3 d, double t_min, double* t_out, Vec3* n_out) {
  const double ox = o.x - c.cx, oy = o.y - c.cy;
  const double a = d.x * d.x + d.y * d.y;
  double best = kInf;
  Vec3 n{};
  if (a > 1e-12) {
    const double b = 2 * (ox * d.x + oy * d.y), cc = ox * ox + oy * oy - c.r * c.r;
    const double disc = b * b - 4 * a * cc;
    if (disc >= 0) {
      const double t = (-b - std::sqrt(disc)) / (2 * a);
      const double z = o.z + t * d.z;
      if (t > t_min && z >= c.z0 && z <= c.z1) {
        best = t;
        n = {(ox + t * d.x) / c.r, (oy + t * d.y) / c.r, 0};
      }
    }
  }
  if (std::fabs(d.z) > 1e-12) {  // the top cap
    const double t = (c.z1 - o.z) / d.z;
    const double x = ox + t * d.x, y = oy + t * d.y;
    if (t > t_min && t < best && x * x + y * y <= c.r * c.r) {
      best = t;
      n = {0, 0, 1};
    }
  }
  if (best == kInf) return false;
  *t_out = best;
  *n_out = n;
  return true;
}

bool ray_sphere(const Sphere& s, Vec3 o, Vec3 d, double t_min, double* t_out, Vec3* n_out) {
  const Vec3 oc = o - Vec3{s.cx, s.cy, s.cz};
  const double b = dot(oc, d), c = dot(oc, oc) - s.r * s.r;
  const double disc = b * b - c;
  if (disc < 0) return false;
  double t = -b - std::sqrt(disc);
  if (t <= t_min) t = -b + std::sqrt(disc);
  if (t <= t_min) return false;
  const Vec3 p = o + d * t;
  if (p.z < 0) return false;  // below the ground
  *t_out = t;
  *n_out = (p - Vec3{s.cx, s.cy, s.cz}) * (1.0 / s.r);
  return true;
}

}  // namespace

Scene::Scene(const Town& town) : town_(town) {
  cells_ = int((town.extent - 2 * origin_) / cell_) + 1;
  grid_.resize(size_t(cells_) * cells_);
  auto add = [&](double x0, double y0, double x1, double y1, Ref r) {
    const int i0 = std::max(0, int((x0 - origin_) / cell_)),
              i1 = std::min(cells_ - 1, int((x1 - origin_) / cell_));
    const int j0 = std::max(0, int((y0 - origin_) / cell_)),
              j1 = std::min(cells_ - 1, int((y1 - origin_) / cell_));
    for (int i = i0; i <= i1; ++i)
      for (int j = j0; j <= j1; ++j) grid_[size_t(j) * cells_ + i].push_back(r);
  };
  for (size_t k = 0; k < town.boxes.size(); ++k) {
    const Box& b = town.boxes[k];
    add(b.x0, b.y0, b.x1, b.y1, {0, int(k)});
  }
  for (size_t k = 0; k < town.cylinders.size(); ++k) {
    const Cylinder& c = town.cylinders[k];
    add(c.cx - c.r, c.cy - c.r, c.cx + c.r, c.cy + c.r, {1, int(k)});
  }
  lamps_.resize(grid_.size());
  for (size_t k = 0; k < town.spheres.size(); ++k) {
    const Sphere& s = town.spheres[k];
    add(s.cx - s.r, s.cy - s.r, s.cx + s.r, s.cy + s.r, {2, int(k)});
    if (s.lamp) {
      const int i = std::clamp(int((s.cx - origin_) / cell_), 0, cells_ - 1);
      const int j = std::clamp(int((s.cy - origin_) / cell_), 0, cells_ - 1);
      lamps_[size_t(j) * cells_ + i].push_back({s.cx, s.cy, s.cz});
    }
  }
}

Color Scene::night_light(const Hit& h, Vec3 d, const Lighting& L) const {
  double lamps = 0;
  if (L.lamp_intensity > 0) {
    const int reach = int(std::ceil(kLampReach / cell_));
    const int ci = int((h.point.x - origin_) / cell_), cj = int((h.point.y - origin_) / cell_);
    for (int j = std::max(0, cj - reach); j <= std::min(cells_ - 1, cj + reach); ++j) {
      for (int i = std::max(0, ci - reach); i <= std::min(cells_ - 1, ci + reach); ++i) {
        for (const Vec3& p : lamps_[size_t(j) * cells_ + i]) {
          const Vec3 v = p - h.point;
          const double d2 = dot(v, v);
          if (d2 > kLampReach * kLampReach) continue;
          const double ndl = dot(h.normal, v) / std::sqrt(d2);
          if (ndl > 0) lamps += L.lamp_intensity * ndl / d2;
        }
      }
    }
  }
  // Headlights: on what is ahead and below the horizon, fading with distance.
  const double cone = std::clamp(1.0 - 8.0 * std::max(0.0, d.z + 0.03), 0.0, 1.0);
  const double head =
      L.headlight * cone * std::max(0.0, -dot(h.normal, d)) / (1.0 + (h.t / 9.0) * (h.t / 9.0));
  return {float(L.lamp.r * lamps + head), float(L.lamp.g * lamps + head),
          float(L.lamp.b * lamps + 0.95 * head)};
}

Color Scene::surface(const Box& b, Vec3 p, Vec3 n) const {
  if (n.z > 0.5) {  // roof
    return {b.base.r * 0.55f, b.base.g * 0.55f, b.base.b * 0.55f};
  }
  const double u = std::fabs(n.x) > 0.5 ? p.y : p.x;
  switch (b.material) {
    case Material::kFacade: {
      const double fz = frac(p.z / b.floor_h), fu = frac(u / b.window_w + 0.25 * b.id);
      const bool ground_floor = p.z < b.floor_h;
      const bool window = fz > 0.3 && fz < 0.8 && fu > 0.2 && fu < 0.8;
      if (ground_floor && fu > 0.35 && fu < 0.65 && fz < 0.75) return b.second;  // doors
      return window && !ground_floor ? b.second : b.base;
    }
    case Material::kStriped: return frac(p.z / 2.0) < 0.5 ? b.base : b.second;
    case Material::kBillboard:
      return (int(std::floor(u)) + int(std::floor(p.z))) % 2 ? b.base : b.second;
    case Material::kPlain: break;
  }
  return b.base;
}

bool Scene::hit_cell(int cx, int cy, Vec3 o, Vec3 d, double t_min, double t_max, Hit* hit) const {
  bool any = false;
  for (const Ref& r : grid_[size_t(cy) * cells_ + cx]) {
    double t;
    Vec3 n;
    bool ok = false;
    Color albedo;
    if (r.kind == 0) {
      ok = ray_box(town_.boxes[r.index], o, d, t_min, &t, &n);
    } else if (r.kind == 1) {
      ok = ray_cylinder(town_.cylinders[r.index], o, d, t_min, &t, &n);
      albedo = town_.cylinders[r.index].color;
    } else {
      ok = ray_sphere(town_.spheres[r.index], o, d, t_min, &t, &n);
      albedo = town_.spheres[r.index].color;
    }
    const bool lamp = r.kind == 2 && town_.spheres[r.index].lamp;
    if (!ok || t >= t_max || t >= hit->t) continue;
    hit->t = t;
    hit->point = o + d * t;
    hit->normal = n;
    hit->albedo = r.kind == 0 ? surface(town_.boxes[r.index], hit->point, n) : albedo;
    hit->sky = false;
    hit->lamp = lamp;
    any = true;
  }
  return any;
}

bool Scene::intersect(Vec3 o, Vec3 d, double t_max, Hit* hit) const {
  hit->t = kInf;
  hit->sky = true;
  // The ground plane first; objects in front of it replace it.
  if (d.z < -1e-9) {
    const double t = -o.z / d.z;
    if (t > 1e-6 && t < t_max) {
      hit->t = t;
      hit->point = o + d * t;
      hit->normal = {0, 0, 1};
      hit->albedo = town_.ground(hit->point.x, hit->point.y);
      hit->sky = false;
      hit->lamp = false;
    }
  }
  // 2-D DDA over the grid cells.
  double gx = (o.x - origin_) / cell_, gy = (o.y - origin_) / cell_;
  double t_enter = 0.0;
  const double span = cells_;
  if (gx < 0 || gy < 0 || gx >= span || gy >= span) {  // start outside: clip to the grid
    double t0 = 0, t1 = kInf;
    for (int a = 0; a < 2; ++a) {
      const double oo = a ? gy : gx, dd = (a ? d.y : d.x) / cell_;
      if (std::fabs(dd) < 1e-12) {
        if (oo < 0 || oo >= span) return !hit->sky;
        continue;
      }
      double ta = (0 - oo) / dd, tb = (span - oo) / dd;
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    if (t0 > t1) return !hit->sky;
    t_enter = t0 + 1e-9;
    gx += t_enter * d.x / cell_;
    gy += t_enter * d.y / cell_;
  }
  int cx = std::clamp(int(gx), 0, cells_ - 1), cy = std::clamp(int(gy), 0, cells_ - 1);
  const int sx = d.x > 0 ? 1 : -1, sy = d.y > 0 ? 1 : -1;
  const double dtx = std::fabs(d.x) > 1e-12 ? cell_ / std::fabs(d.x) : kInf;
  const double dty = std::fabs(d.y) > 1e-12 ? cell_ / std::fabs(d.y) : kInf;
  double tx = std::fabs(d.x) > 1e-12
                  ? t_enter + ((d.x > 0 ? (cx + 1 - gx) : (gx - cx)) * cell_) / std::fabs(d.x)
                  : kInf;
  double ty = std::fabs(d.y) > 1e-12
                  ? t_enter + ((d.y > 0 ? (cy + 1 - gy) : (gy - cy)) * cell_) / std::fabs(d.y)
                  : kInf;
  for (int steps = 0; steps < 4 * cells_; ++steps) {
    const double t_exit = std::min(tx, ty);
    hit_cell(cx, cy, o, d, 1e-6, t_max, hit);
    if (hit->t <= t_exit || t_exit > t_max) break;
    if (tx < ty) {
      cx += sx;
      tx += dtx;
    } else {
      cy += sy;
      ty += dty;
    }
    if (cx < 0 || cy < 0 || cx >= cells_ || cy >= cells_) break;
  }
  return !hit->sky;
}

Color Scene::shade(Vec3 o, Vec3 d, const Lighting& L) const {
  Hit h;
  Color c;
  if (!intersect(o, d, 2000.0, &h)) {
    const double up = std::clamp(d.z, 0.0, 1.0);
    const double k = std::sqrt(up);
    c = {float(L.sky_horizon.r * (1 - k) + L.sky_zenith.r * k),
         float(L.sky_horizon.g * (1 - k) + L.sky_zenith.g * k),
         float(L.sky_horizon.b * (1 - k) + L.sky_zenith.b * k)};
    const double sun = dot(d, L.sun_dir);
    const bool sunlit = L.sun.r + L.sun.g + L.sun.b > 0.3f;
    if (sun > 0.9995 && sunlit) c = {1.0f, 0.98f, 0.9f};
    return c;
  }
  const bool night = L.lamp_intensity > 0 || L.headlight > 0;
  if (h.lamp && night) {  // a lit street light: its own colour, through the haze
    c = {1.0f, 0.93f, 0.75f};
  } else {
    double diffuse = std::max(0.0, dot(h.normal, L.sun_dir));
    if (diffuse > 0) {  // hard shadow
      Hit s;
      if (intersect(h.point + h.normal * 1e-4, L.sun_dir, 400.0, &s)) diffuse = 0;
    }
    const Color extra = night ? night_light(h, d, L) : Color{};
    c = {float(h.albedo.r * (L.ambient.r + L.sun.r * diffuse + extra.r)),
         float(h.albedo.g * (L.ambient.g + L.sun.g * diffuse + extra.g)),
         float(h.albedo.b * (L.ambient.b + L.sun.b * diffuse + extra.b))};
  }
  const float f = float(std::exp(-h.t / L.fog_distance));
  c = {c.r * f + L.fog.r * (1 - f), c.g * f + L.fog.g * (1 - f), c.b * f + L.fog.b * (1 - f)};
  return c;
}

}  // namespace aprt::synth
