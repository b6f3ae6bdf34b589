#include "tools/synth/town.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace aprt::synth {
namespace {

Color hsv(double h, double s, double v) {
  h = std::fmod(h, 1.0) * 6.0;
  const int i = int(h);
  const double f = h - i, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  switch (i) {
    case 0: return {float(v), float(t), float(p)};
    case 1: return {float(q), float(v), float(p)};
    case 2: return {float(p), float(v), float(t)};
    case 3: return {float(p), float(q), float(v)};
    case 4: return {float(t), float(p), float(v)};
    default: return {float(v), float(p), float(q)};
  }
}

double nearest_line(double v, double spacing, double lo, double hi) {
  const double k = std::round(v / spacing) * spacing;
  return std::clamp(k, lo, hi);
}

}  // namespace

bool Town::on_road(double x, double y) const {
  if (x < -road_half || y < -road_half || x > extent + road_half || y > extent + road_half) {
    return false;
  }
  const double dr = std::hypot(x - roundabout.x, y - roundabout.y);
  if (dr < island_r) return false;
  if (dr <= roundabout_r) return true;
  const double sx = nearest_line(x, block, 0, extent), sy = nearest_line(y, block, 0, extent);
  return std::fabs(x - sx) <= road_half || std::fabs(y - sy) <= road_half;
}

Color Town::ground(double x, double y) const {
  const Color asphalt{0.22f, 0.22f, 0.24f}, marking{0.85f, 0.85f, 0.8f};
  const Color sidewalk_c{0.55f, 0.54f, 0.52f}, grass{0.24f, 0.42f, 0.18f};
  const Color lot{0.45f, 0.42f, 0.38f};
  const double dr = std::hypot(x - roundabout.x, y - roundabout.y);
  if (dr < island_r) return grass;
  if (dr <= roundabout_r) {
    // Dashed ring in the middle of the roundabout lane.
    const double mid = 0.5 * (island_r + roundabout_r);
    const double ang = std::atan2(y - roundabout.y, x - roundabout.x) * mid;
    if (std::fabs(dr - mid) < 0.15 && std::fmod(ang + 1000.0, 6.0) < 3.0) return marking;
    return asphalt;
  }
  const bool inside = x > -road_half - sidewalk && y > -road_half - sidewalk &&
                      x < extent + road_half + sidewalk && y < extent + road_half + sidewalk;
  if (!inside) return grass;
  const double sx = nearest_line(x, block, 0, extent), sy = nearest_line(y, block, 0, extent);
  const double dx = std::fabs(x - sx), dy = std::fabs(y - sy);
  if (dx <= road_half || dy <= road_half) {
    // Dashed centre lines; none inside intersections.
    const bool in_x_road = dx <= road_half, in_y_road = dy <= road_half;
    if (in_x_road && !in_y_road && dx < 0.15 && std::fmod(y + 1000.0, 6.0) < 3.0) return marking;
    if (in_y_road && !in_x_road && dy < 0.15 && std::fmod(x + 1000.0, 6.0) < 3.0) return marking;
    // Stop lines before intersections.
    if (in_x_road && !in_y_road && dy < road_half + 1.2 && dy > road_half + 0.8) return marking;
    if (in_y_road && !in_x_road && dx < road_half + 1.2 && dx > road_half + 0.8) return marking;
    return asphalt;
  }
  if (dx <= road_half + sidewalk || dy <= road_half + sidewalk) return sidewalk_c;
  const int bx = int(x / block), by = int(y / block);
  if (bx == park_bx && by == park_by) return grass;
  return lot;
}

Town make_town(uint32_t seed) {
  Town t;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  t.roundabout = {t.extent / 2, t.extent / 2, 0};
  const int blocks = t.streets() - 1;
  t.park_bx = 1;
  t.park_by = 2;
  uint32_t id = 1;
  const double margin = t.road_half + t.sidewalk + 1.0;
  auto clear_of_roundabout = [&](double x0, double y0, double x1, double y1) {
    const double cx = std::clamp(t.roundabout.x, x0, x1), cy = std::clamp(t.roundabout.y, y0, y1);
    return std::hypot(cx - t.roundabout.x, cy - t.roundabout.y) > t.roundabout_r + 6.0;
  };
  for (int bx = 0; bx < blocks; ++bx) {
    for (int by = 0; by < blocks; ++by) {
      const double ox = bx * t.block + margin, oy = by * t.block + margin;
      const double size = t.block - 2 * margin;
      if (bx == t.park_bx && by == t.park_by) {  // the park: trees on grass
        for (int k = 0; k < 22; ++k) {
          const double x = ox + 2 + u(rng) * (size - 4), y = oy + 2 + u(rng) * (size - 4);
          const double r = 1.8 + 1.2 * u(rng);
          t.cylinders.push_back({x, y, 0.25, 0.0, 3.5, {0.35f, 0.24f, 0.15f}, id++});
          t.spheres.push_back({x, y, 3.5 + r * 0.8, r, hsv(0.25 + 0.08 * u(rng), 0.6, 0.45), id++});
        }
        continue;
      }
      // Lots: 1, 2 or 4 buildings.
      const int mode = int(u(rng) * 3);
      const int nx = mode == 2 ? 2 : (mode == 1 ? 2 : 1), ny = mode == 2 ? 2 : 1;
      const bool split_y = mode == 1 && u(rng) < 0.5;
      const int cols = split_y ? 1 : nx, rows = split_y ? 2 : ny;
      const double gap = 2.5;
      const double w = (size - gap * (cols - 1)) / cols, h = (size - gap * (rows - 1)) / rows;
      for (int i = 0; i < cols; ++i) {
        for (int j = 0; j < rows; ++j) {
          const double x0 = ox + i * (w + gap), y0 = oy + j * (h + gap);
          const double x1 = x0 + w * (0.8 + 0.2 * u(rng)), y1 = y0 + h * (0.8 + 0.2 * u(rng));
          if (!clear_of_roundabout(x0, y0, x1, y1)) continue;
          Box b{};
          b.x0 = x0;
          b.y0 = y0;
          b.z0 = 0;
          b.x1 = x1;
          b.y1 = y1;
          b.z1 = 6.0 + u(rng) * (u(rng) < 0.2 ? 40.0 : 22.0);
          const double pick = u(rng);
          b.material = pick < 0.6 ? Material::kFacade
                                  : (pick < 0.85 ? Material::kStriped : Material::kPlain);
          b.base = hsv(u(rng), 0.15 + 0.55 * u(rng), 0.45 + 0.45 * u(rng));
          b.second = u(rng) < 0.5 ? Color{0.12f, 0.16f, 0.22f} : hsv(u(rng), 0.6, 0.35);
          b.floor_h = 2.8 + 0.8 * u(rng);
          b.window_w = 1.8 + 2.0 * u(rng);
          b.id = id++;
          t.boxes.push_back(b);
        }
      }
    }
  }
  // Landmarks.
  const double bc = t.block / 2;
  t.cylinders.push_back({3 * t.block + bc, bc, 3.0, 0.0, 62.0, {0.85f, 0.85f, 0.88f}, id++});
  t.spheres.push_back({3 * t.block + bc, bc, 64.0, 5.0, {0.85f, 0.1f, 0.1f}, id++});
  t.spheres.push_back({2 * t.block + bc, 3 * t.block + bc, 0.0, 11.0, {0.15f, 0.3f, 0.8f}, id++});
  t.cylinders.push_back({t.roundabout.x, t.roundabout.y, 1.5, 0.0, 7.0, {0.8f, 0.65f, 0.2f}, id++});
  t.spheres.push_back({t.roundabout.x, t.roundabout.y, 8.5, 2.0, {0.9f, 0.75f, 0.25f}, id++});
  {
    Box bb{};
    bb.x0 = bc - 6;
    bb.x1 = bc + 6;
    bb.y0 = 3 * t.block + margin;
    bb.y1 = bb.y0 + 0.6;
    bb.z0 = 4.0;
    bb.z1 = 10.0;
    bb.material = Material::kBillboard;
    bb.base = {0.95f, 0.8f, 0.1f};
    bb.second = {0.1f, 0.1f, 0.6f};
    bb.id = id++;
    t.boxes.push_back(bb);
    Box post = bb;
    post.material = Material::kPlain;
    post.x0 = bc - 0.3;
    post.x1 = bc + 0.3;
    post.z0 = 0.0;
    post.z1 = 4.0;
    post.base = {0.3f, 0.3f, 0.3f};
    post.id = id++;
    t.boxes.push_back(post);
  }
  // Street lights every 20 m on both sides of every street; trees on some streets.
  const double side = t.road_half + 1.0;
  for (int s = 0; s < t.streets(); ++s) {
    const double c = s * t.block;
    for (double a = 10.0; a < t.extent; a += 20.0) {
      for (int horizontal = 0; horizontal < 2; ++horizontal) {
        for (int sign = -1; sign <= 1; sign += 2) {
          const double x = horizontal ? a : c + sign * side, y = horizontal ? c + sign * side : a;
          if (std::hypot(x - t.roundabout.x, y - t.roundabout.y) < t.roundabout_r + 3) continue;
          if (std::fmod(a, t.block) < 8 || std::fmod(a, t.block) > t.block - 8) continue;
          t.cylinders.push_back({x, y, 0.12, 0.0, 6.0, {0.3f, 0.3f, 0.32f}, id++});
          t.spheres.push_back({x, y, 6.1, 0.35, {1.0f, 0.95f, 0.7f}, id++, true});
          if ((s + horizontal) % 2 == 0 && sign == 1) {
            const double tx = horizontal ? a + 10 : x, ty = horizontal ? y : a + 10;
            if (tx < t.extent - 8 && ty < t.extent - 8) {
              t.cylinders.push_back({tx, ty, 0.2, 0.0, 3.0, {0.35f, 0.24f, 0.15f}, id++});
              t.spheres.push_back({tx, ty, 4.2, 1.6, hsv(0.28, 0.55, 0.4), id++});
            }
          }
        }
      }
    }
  }
  return t;
}

}  // namespace aprt::synth
