#include "tools/synth/drive.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>

namespace aprt::synth {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct P2 {
  double x, y;
};

P2 bezier(P2 a, P2 c, P2 b, double t) {
  const double u = 1 - t;
  return {u * u * a.x + 2 * u * t * c.x + t * t * b.x, u * u * a.y + 2 * u * t * c.y + t * t * b.y};
}

// Densely sampled polyline of the route, later resampled at the spacing.
void append(std::vector<P2>& line, P2 p) {
  if (line.empty() || std::hypot(p.x - line.back().x, p.y - line.back().y) > 1e-6)
    line.push_back(p);
}

}  // namespace

std::vector<VehiclePose> drive(const Town& town, const RouteOptions& opt) {
  const int n = town.streets();
  const int mid = n / 2;  // the roundabout node
  std::mt19937 rng(opt.seed);
  auto node_xy = [&](int i, int j) { return P2{i * town.block, j * town.block}; };
  auto neighbours = [&](int i, int j) {
    std::vector<std::pair<int, int>> out;
    const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
    for (int k = 0; k < 4; ++k) {
      const int a = i + di[k], b = j + dj[k];
      if (a >= 0 && b >= 0 && a < n && b < n) out.push_back({a, b});
    }
    return out;
  };
  // Node sequence: a walk preferring directed edges not yet driven, no U-turns.
  std::set<std::tuple<int, int, int, int>> driven;
  const int total_edges = 2 * 2 * n * (n - 1);
  std::vector<std::pair<int, int>> nodes{{0, 0}};
  std::pair<int, int> prev{-1, -1};
  double length = 0;
  while (length < opt.max_length && (!opt.cover_all || int(driven.size()) < total_edges)) {
    // Plain copies, not a structured binding: clang 14 cannot capture those in a lambda.
    const int i = nodes.back().first, j = nodes.back().second;
    auto nb = neighbours(i, j);
    std::shuffle(nb.begin(), nb.end(), rng);
    std::stable_sort(nb.begin(), nb.end(), [&](auto a, auto b) {
      const bool na = driven.count({i, j, a.first, a.second}),
                 nb2 = driven.count({i, j, b.first, b.second});
      return !na && nb2;
    });
    auto next = nb.front();
    if (next == prev && nb.size() > 1) next = nb[1];
    driven.insert({i, j, next.first, next.second});
    prev = {i, j};
    nodes.push_back(next);
    length += town.block;
    if (nodes.size() > size_t(20 * total_edges)) break;
  }
  // Geometry: lane centre lines, corners as quadratic curves, the roundabout as an arc.
  const double lane = town.road_half / 2.0;
  const double ring = 0.5 * (town.island_r + town.roundabout_r);
  std::vector<P2> line;
  for (size_t k = 0; k + 1 < nodes.size(); ++k) {
    const P2 a = node_xy(nodes[k].first, nodes[k].second);
    const P2 b = node_xy(nodes[k + 1].first, nodes[k + 1].second);
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    const P2 d{(b.x - a.x) / len, (b.y - a.y) / len};
    const P2 right{d.y, -d.x};
    const bool a_round = nodes[k].first == mid && nodes[k].second == mid;
    const bool b_round = nodes[k + 1].first == mid && nodes[k + 1].second == mid;
    const double ca = a_round ? town.roundabout_r + 1.0 : town.road_half + 1.0;
    const double cb = b_round ? town.roundabout_r + 1.0 : town.road_half + 1.0;
    const P2 s{a.x + d.x * ca + right.x * lane, a.y + d.y * ca + right.y * lane};
    const P2 e{b.x - d.x * cb + right.x * lane, b.y - d.y * cb + right.y * lane};
    // Connect from the previous segment's end through node a.
    if (!line.empty()) {
      const P2 from = line.back();
      if (a_round) {
        const double a0 = std::atan2(from.y - a.y, from.x - a.x);
        double a1 = std::atan2(s.y - a.y, s.x - a.x);
        while (a1 <= a0 + 0.3) a1 += 2 * kPi;  // counter-clockwise, at least a little
        for (double t = a0; t < a1; t += 0.05)
          append(line, {a.x + ring * std::cos(t), a.y + ring * std::sin(t)});
      } else {
        // Control point: where the incoming and outgoing lane lines meet.
        const P2 din{(a.x - line.back().x), (a.y - line.back().y)};
        const double dl = std::hypot(din.x, din.y);
        const P2 u{din.x / dl, din.y / dl};
        const double cross = u.x * d.y - u.y * d.x;
        P2 c{(from.x + s.x) / 2, (from.y + s.y) / 2};
        if (std::fabs(cross) > 1e-6) {
          const double t = ((s.x - from.x) * d.y - (s.y - from.y) * d.x) / cross;
          c = {from.x + u.x * t, from.y + u.y * t};
        }
        for (double t = 0.05; t < 1.0; t += 0.05) append(line, bezier(from, c, s, t));
      }
    }
    append(line, s);
    append(line, e);
  }
  // Resample at the spacing; yaw from the tangent; slow jitter on top.
  std::vector<VehiclePose> out;
  std::uniform_real_distribution<double> phase(0, 2 * kPi);
  const double p1 = phase(rng), p2 = phase(rng), p3 = phase(rng);
  double carry = 0, s_total = 0;
  for (size_t k = 0; k + 1 < line.size(); ++k) {
    const P2 a = line[k], b = line[k + 1];
    const double seg = std::hypot(b.x - a.x, b.y - a.y);
    double pos = carry;
    while (pos < seg) {
      const double t = pos / seg;
      const double yaw = std::atan2(b.y - a.y, b.x - a.x);
      const double s = s_total + pos;
      const double lateral = opt.lane_jitter * std::sin(s / 23.0 + p1) * std::cos(s / 61.0 + p2);
      const double dyaw = opt.yaw_jitter_deg * kPi / 180 * std::sin(s / 17.0 + p3);
      out.push_back({a.x + (b.x - a.x) * t + std::sin(yaw) * lateral,
                     a.y + (b.y - a.y) * t - std::cos(yaw) * lateral, yaw + dyaw});
      if (s_total + pos > opt.max_length) return out;
      pos += opt.spacing;
    }
    carry = pos - seg;
    s_total += seg;
  }
  return out;
}

}  // namespace aprt::synth
