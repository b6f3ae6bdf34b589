// The row loop every tiled kernel shares: full tiles of MR rows, then one
// tile of the rows left, each with the row count as a compile-time constant
// (so accumulators stay in registers). `tile(R, r)` is a generic lambda taking
// std::integral_constant<int, R> and the first row.
#pragma once

#include <type_traits>

namespace aprt::kernels {

template <int N, class F>
inline void row_tile_rest(int rows, int r, F& tile) {
  if constexpr (N > 0) {
    if (rows == N) {
      tile(std::integral_constant<int, N>{}, r);
    } else {
      row_tile_rest<N - 1>(rows, r, tile);
    }
  }
}

template <int MR, class F>
inline void for_row_tiles(int r0, int r1, F&& tile) {
  int r = r0;
  for (; r + MR <= r1; r += MR) tile(std::integral_constant<int, MR>{}, r);
  row_tile_rest<MR - 1>(r1 - r, r, tile);
}

}  // namespace aprt::kernels
