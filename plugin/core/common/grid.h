// The taxel grid: an n x n lattice of square cells in the skin's tangent plane
// at the pad's pole (pad frame x, y), centred on the pole.
#ifndef MJTOUCH_COMMON_GRID_H_
#define MJTOUCH_COMMON_GRID_H_

#include <algorithm>
#include <climits>
#include <cstddef>
#include <vector>

namespace mjtouch {

struct TaxelGrid {
  int n = 0;            // cells per side
  double pitch_m = 0;   // cell side
  double offset_m = 0;  // every cell centre moved by this in x and in y (sub-cell offset grids)

  size_t Size() const { return static_cast<size_t>(n) * n; }
  // Centre of cell index i along one axis (pad frame, m).
  double Centre(int i) const { return (i - 0.5 * (n - 1)) * pitch_m + offset_m; }
  double Area() const { return pitch_m * pitch_m; }
  double HalfExtent() const { return 0.5 * n * pitch_m; }
  // Nearest cell index to coordinate x_m (clamped).
  int Nearest(double x_m) const {
    int i = static_cast<int>((x_m - offset_m) / pitch_m + 0.5 * (n - 1) + 0.5 + 1e6) - 1000000;
    return i < 0 ? 0 : (i >= n ? n - 1 : i);
  }
};

// A rectangle of grid cells [i0, i0 + nx) x [j0, j0 + ny).
struct CellBox {
  int i0 = 0, j0 = 0, nx = 0, ny = 0;
  bool empty() const { return nx <= 0 || ny <= 0; }
  static CellBox All(const TaxelGrid& grid) { return CellBox{0, 0, grid.n, grid.n}; }
};

// The bounding rectangle of cells added one at a time (inclusive bounds;
// empty until the first Add, or starting from a box).
struct CellBounds {
  int i0 = INT_MAX, j0 = INT_MAX, i1 = INT_MIN, j1 = INT_MIN;
  CellBounds() = default;
  explicit CellBounds(const CellBox& b)
      : i0(b.i0), j0(b.j0), i1(b.i0 + b.nx - 1), j1(b.j0 + b.ny - 1) {}
  void Add(int i, int j) { AddRow(i, i, j); }
  // The cells [lo, hi] of row j.
  void AddRow(int lo, int hi, int j) {
    i0 = std::min(i0, lo);
    i1 = std::max(i1, hi);
    j0 = std::min(j0, j);
    j1 = std::max(j1, j);
  }
  bool empty() const { return i1 < i0 || j1 < j0; }
  CellBox Box() const { return empty() ? CellBox{} : CellBox{i0, j0, i1 - i0 + 1, j1 - j0 + 1}; }
};

// Cells with nonzero traction as row runs: for each grid row j with contact,
// [i_begin, i_end) of active cells.
struct ActiveRuns {
  std::vector<int> row, begin, end;
  void Clear() {
    row.clear();
    begin.clear();
    end.clear();
  }
  void Add(int j, int i_begin, int i_end) {
    row.push_back(j);
    begin.push_back(i_begin);
    end.push_back(i_end);
  }
  int Count() const {
    int c = 0;
    for (size_t k = 0; k < row.size(); ++k) c += end[k] - begin[k];
    return c;
  }
};

}  // namespace mjtouch

#endif  // MJTOUCH_COMMON_GRID_H_
