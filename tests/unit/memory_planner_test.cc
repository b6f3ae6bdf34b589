#include "runtime/engine/memory_planner.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace aprt {
namespace {

bool live_together(const PlanBuffer& a, const PlanBuffer& b) {
  return a.first <= b.last && b.first <= a.last;
}

TEST(MemoryPlanner, NeverOverlapsLiveBuffersOnRandomGraphs) {
  std::mt19937 rng(7);
  for (int round = 0; round < 200; ++round) {
    const int n = 1 + int(rng() % 60);
    std::vector<PlanBuffer> b(static_cast<size_t>(n));
    for (auto& x : b) {
      x.bytes = 1 + rng() % 5000;
      x.first = int(rng() % 40) - 1;
      x.last = x.first + int(rng() % 10);
    }
    const PlanSummary s = plan_greedy_by_size(b.data(), n, 64);
    for (int i = 0; i < n; ++i) {
      EXPECT_EQ(b[i].offset % 64, 0u);
      EXPECT_LE(b[i].offset + b[i].bytes, s.arena_bytes);
      for (int j = i + 1; j < n; ++j) {
        if (!live_together(b[i], b[j])) continue;
        const bool disjoint =
            b[i].offset + b[i].bytes <= b[j].offset || b[j].offset + b[j].bytes <= b[i].offset;
        ASSERT_TRUE(disjoint) << "round " << round << ": buffers " << i << " and " << j;
      }
    }
    EXPECT_GE(s.arena_bytes, s.lower_bound_bytes);
    EXPECT_LE(s.arena_bytes, s.sum_bytes);
  }
}

TEST(MemoryPlanner, ReusesMemoryOfAChain) {
  // A chain a -> b -> c -> d: only neighbours are live together.
  std::vector<PlanBuffer> b = {{1000, 0, 1, 0}, {1000, 1, 2, 0}, {1000, 2, 3, 0}, {1000, 3, 4, 0}};
  const PlanSummary s = plan_greedy_by_size(b.data(), 4, 64);
  EXPECT_EQ(s.arena_bytes, 2 * 1024u);
  EXPECT_EQ(s.lower_bound_bytes, 2 * 1024u);
  EXPECT_EQ(s.sum_bytes, 4 * 1024u);
}

}  // namespace
}  // namespace aprt
