// Places activation tensors in one arena from their lifetimes.
//
// Greedy by size (the strategy TFLM's GreedyMemoryPlanner uses): largest
// buffers first, each at the lowest offset that does not overlap a placed
// buffer whose lifetime intersects its own. Lifetimes are op indices,
// inclusive: a buffer is live from the op that writes it to the last op that
// reads it.
#pragma once

#include <cstddef>

namespace aprt {

struct PlanBuffer {
  size_t bytes = 0;
  int first = 0;      // op index that writes it (-1: live before the first op)
  int last = 0;       // last op index that reads it
  size_t offset = 0;  // result
};

struct PlanSummary {
  size_t arena_bytes = 0;        // what the plan needs
  size_t sum_bytes = 0;          // every buffer separately (no reuse)
  size_t lower_bound_bytes = 0;  // largest sum of simultaneously live buffers
};

// Fills every buffer's offset (multiples of `align`). Runs at load time only.
PlanSummary plan_greedy_by_size(PlanBuffer* buffers, int count, size_t align);

}  // namespace aprt
