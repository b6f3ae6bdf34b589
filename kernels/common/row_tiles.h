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

// Column panels [p0, p1) of nr columns (the last one may be narrower), each
// over rows [r0, r1) in tiles: tile(R, r, j0, ncols, panel_index).
template <int MR, int NR, class F>
inline void for_panel_tiles(int n, int r0, int r1, int p0, int p1, F&& tile) {
  for (int p = p0; p < p1; ++p) {
    const int j0 = p * NR, ncols = n - j0 < NR ? n - j0 : NR;
    for_row_tiles<MR>(r0, r1, [&](auto rows, int r) { tile(rows, r, j0, ncols, p); });
  }
}

}  // namespace aprt::kernels
