#include "runtime/engine/memory_planner.h"

#include <algorithm>
#include <vector>

namespace aprt {
namespace {

size_t round_up(size_t n, size_t a) {
  return (n + a - 1) / a * a;
}

bool overlaps(const PlanBuffer& a, const PlanBuffer& b) {
  return a.first <= b.last && b.first <= a.last;
}

}  // namespace

PlanSummary plan_greedy_by_size(PlanBuffer* buffers, int count, size_t align) {
  PlanSummary s;
  std::vector<int> order_storage(static_cast<size_t>(count));
  int* order = order_storage.data();
  for (int i = 0; i < count; ++i) {
    order[i] = i;
    s.sum_bytes += round_up(buffers[i].bytes, align);
  }
  std::stable_sort(order, order + count,
                   [&](int a, int b) { return buffers[a].bytes > buffers[b].bytes; });
  std::vector<int> placed;
  placed.reserve(count);
  std::vector<int> live;
  live.reserve(count);
  for (int n = 0; n < count; ++n) {
    PlanBuffer& cur = buffers[order[n]];
    const size_t need = round_up(cur.bytes, align);
    live.clear();
    for (int p : placed) {
      if (overlaps(buffers[p], cur)) live.push_back(p);
    }
    std::sort(live.begin(), live.end(),
              [&](int a, int b) { return buffers[a].offset < buffers[b].offset; });
    size_t candidate = 0;
    for (int p : live) {
      const PlanBuffer& o = buffers[p];
      if (o.offset >= candidate + need) break;  // the gap before `o` fits
      candidate = std::max(candidate, round_up(o.offset + o.bytes, align));
    }
    cur.offset = candidate;
    s.arena_bytes = std::max(s.arena_bytes, candidate + need);
    placed.push_back(order[n]);
  }
  // Liveness lower bound: at each op, the sum of live buffers.
  int lo = 0, hi = 0;
  for (int i = 0; i < count; ++i) {
    lo = std::min(lo, buffers[i].first);
    hi = std::max(hi, buffers[i].last);
  }
  for (int t = lo; t <= hi; ++t) {
    size_t live_sum = 0;
    for (int i = 0; i < count; ++i) {
      if (buffers[i].first <= t && t <= buffers[i].last)
        live_sum += round_up(buffers[i].bytes, align);
    }
    s.lower_bound_bytes = std::max(s.lower_bound_bytes, live_sum);
  }
  return s;
}

}  // namespace aprt
