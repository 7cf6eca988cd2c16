// RenderGap's fast path for a face (plane, rectangle, height field) whose
// axes are the pad's (aligned_face.h).
#include "surface/aligned_face.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "common/simd.h"

namespace mjtouch {
namespace surface_detail {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// One row segment [i0, i1) of an aligned face. Branch-free (bitwise &,
// selects, the taken flags in `took`) so that the compiler vectorises it.
struct RowSpan {
  double r7v, r8;  // qz = (t_z + R[6] u) + R[7] v + R[8] z, in that order
  double top, cull, oy, area;
};

// kOverwrite: the cells' old values are taken as +inf / 0 (not read), as
// after a clear (RenderGap's exclusive surface).
template <bool kPlane, bool kOverwrite>
MJTOUCH_TARGET_CLONES void AlignedRow(const RowSpan& r, int i0, int i1, const double* z,
                                      const double* qz0, const double* ox, const double* mean,
                                      double* __restrict gp, double* __restrict cp,
                                      double* __restrict took) {
  for (int i = i0; i < i1; ++i) {
    const double zi = z[i];
    const double qz = qz0[i] + r.r7v + r.r8 * zi;             // qz0 = t_z + R[6] u per column
    const double cov = kPlane ? 1.0 : ox[i] * r.oy / r.area;  // area > 0 (IsAlignedFace)
    const bool reach = (std::abs(zi) < kInf) & !(qz - r.top > r.cull) & (cov > 0.0);
    const double gap = qz - mean[i];  // NaN (per-cell mean) never takes
    const double old_gap = kOverwrite ? kInf : gp[i], old_cov = kOverwrite ? 0.0 : cp[i];
    const bool take = reach & (gap < old_gap);
    gp[i] = take ? gap : old_gap;
    cp[i] = take ? cov : old_cov;
    took[i] = take ? 1.0 : 0.0;
  }
}

// Four double lanes (one AVX2 vector, two SSE2 ones in the default clone).
typedef double v4d __attribute__((vector_size(32)));
typedef long long v4l __attribute__((vector_size(32)));

// Adds the covered cells of [a, b) of one row (lane k: the cells a + k mod 4;
// exact: a minimum or maximum rounds nothing).
MJTOUCH_TARGET_CLONES
void AddExtrema(const double* g, const double* w, int a, int b, Extrema* e) {
  v4d lo, hi;
  std::memcpy(&lo, e->lo, sizeof(lo));
  std::memcpy(&hi, e->hi, sizeof(hi));
  const v4d zero = {0, 0, 0, 0}, inf = {kInf, kInf, kInf, kInf}, ninf = -inf;
  int i = a;
  for (; i + 4 <= b; i += 4) {
    v4d gv, wv;
    std::memcpy(&gv, g + i, sizeof(gv));
    std::memcpy(&wv, w + i, sizeof(wv));
    const v4l in = (wv > zero) & (gv < inf) & (gv > ninf);
    const v4d gs = in ? gv : inf, ws = in ? wv : zero;
    lo = gs < lo ? gs : lo;
    hi = ws > hi ? ws : hi;
  }
  std::memcpy(e->lo, &lo, sizeof(lo));
  std::memcpy(e->hi, &hi, sizeof(hi));
  for (; i < b; ++i) {
    if (!(w[i] > 0.0 && std::abs(g[i]) < kInf)) continue;
    e->lo[0] = std::min(e->lo[0], g[i]);
    e->hi[0] = std::max(e->hi[0], w[i]);
  }
}

}  // namespace

bool IsAlignedFace(const CounterSurface& s, const double R[9], double hx, double hy) {
  using T = CounterSurface::Type;
  if (s.type != T::kPlane && s.type != T::kRectangle && s.type != T::kHeightField) return false;
  return R[1] == 0.0 && R[2] == 0.0 && R[3] == 0.0 && R[5] == 0.0 && hx > 0.0 && hy > 0.0;
}

bool RenderAlignedFace(const TaxelGrid& grid, const std::vector<double>& skin_z,
                       const AlignedFace& f, const SkinBlocks& blocks, const double* block_lb,
                       double* gap_m, double* coverage, Extent* ext, bool covers_only,
                       Extrema* extrema, ActiveRuns* spans, CellBox* overwrite) {
  // overwrite: the cells hold stale values; every cell of the rows and
  // columns of the blocks within reach is written (+inf / 0 where nothing
  // takes), and *overwrite is set to that rectangle.
  if (overwrite) *overwrite = CellBox{};
  using T = CounterSurface::Type;
  const CounterSurface& s = f.s;
  const double* R = f.R;
  const int n = grid.n, B = SkinBlocks::kSide, nb = blocks.nb;
  // Column and row ranges of the blocks within reach.
  CellBounds reach;  // in blocks
  for (int bj = 0; bj < nb; ++bj)
    for (int bi = 0; bi < nb; ++bi)
      if (block_lb[bj * nb + bi] <= f.cull) reach.Add(bi, bj);
  if (reach.empty()) return true;
  const int c0 = reach.i0 * B, c1 = std::min(n, reach.i1 * B + B);
  const int r0 = reach.j0 * B, r1 = std::min(n, reach.j1 * B + B);
  const bool plane = s.type == T::kPlane, hfield = s.type == T::kHeightField;
  const double area = 4.0 * f.hx * f.hy;
  // Per column: x overlap with the face, the footprint's x range and (a
  // height field with equal rows) the texture's mean over the footprint,
  // NaN where it must be computed per cell. Per row: the same in y.
  RenderScratch& scratch = *f.scratch;
  scratch.columns.resize(static_cast<size_t>(7) * n);
  scratch.rows.resize(static_cast<size_t>(3) * n);
  double *ox = scratch.columns.data(), *x0 = ox + n, *x1 = x0 + n, *mean = x1 + n, *u = mean + n;
  double* took = u + n;
  double* qz0 = took + n;  // per column: t_z + R[6] u (qz's first terms)
  double *oy = scratch.rows.data(), *y0 = oy + n, *y1 = y0 + n;
  const bool row_means = hfield && s.rows_identical && s.row_prefix;
  const double scx = hfield ? (s.ncol - 1) / (2.0 * s.half_x_m) : 0.0;
  bool per_cell = false, negative = false;
  // The columns of this face were computed by the last call (RenderGap's
  // covers_only test, then the render, in one RenderGap call): the same
  // inputs, so the same values, not computed again.
  RenderScratch::ColumnKey& last_columns = scratch.columns_key;
  const bool same_columns =
      last_columns.face == &s && last_columns.c0 == c0 && last_columns.c1 == c1;
  if (same_columns) {
    per_cell = last_columns.per_cell;
    negative = last_columns.negative;
  }
  for (int i = c0; i < c1 && !same_columns; ++i) {
    u[i] = grid.Centre(i);
    const double qx = f.t[0] + R[0] * u[i];
    ox[i] = Overlap1D(qx - f.hx, qx + f.hx, -s.half_x_m, s.half_x_m);
    x0[i] = std::max(qx - f.hx, -s.half_x_m);
    x1[i] = std::min(qx + f.hx, s.half_x_m);
    mean[i] = std::numeric_limits<double>::quiet_NaN();
    if (row_means && ox[i] > 0.0) {  // HeightFieldBoxMean's identical-rows branch
      const double sx0 = std::clamp((x0[i] + s.half_x_m) * scx, 0.0, s.ncol - 1.0);
      const double sx1 = std::clamp((x1[i] + s.half_x_m) * scx, 0.0, s.ncol - 1.0);
      if (sx1 - sx0 > 1e-6)
        mean[i] = s.elevation_m * (RowIntegral(s, 0, sx1) - RowIntegral(s, 0, sx0)) / (sx1 - sx0);
    }
    if (!hfield) mean[i] = 0.0;
    per_cell |= mean[i] != mean[i] && ox[i] > 0.0;
    negative |= mean[i] < 0.0;
  }
  last_columns = RenderScratch::ColumnKey{&s, c0, c1, per_cell, negative};
  if (covers_only) return !per_cell && !negative;
  if (overwrite) *overwrite = CellBox{c0, r0, c1 - c0, r1 - r0};
  for (int j = r0; j < r1; ++j) {
    const double qy = f.t[1] + R[4] * grid.Centre(j);
    oy[j] = Overlap1D(qy - f.hy, qy + f.hy, -s.half_y_m, s.half_y_m);
    y0[j] = std::max(qy - f.hy, -s.half_y_m);
    y1[j] = std::min(qy + f.hy, s.half_y_m);
  }
  const double tz = f.t[2], r6 = R[6], r7 = R[7], r8 = R[8], top = s.max_height_m;
  const double cull = f.cull;
  for (int i = c0; i < c1; ++i) qz0[i] = tz + r6 * u[i];
  for (int j = r0; j < r1; ++j) {
    const double v = grid.Centre(j), oyj = oy[j];
    const int bj = j / B;
    int lo = n, hi = -1;
    for (int bi = reach.i0; bi <= reach.i1; ++bi) {
      if (!(block_lb[bj * nb + bi] <= cull)) {
        if (overwrite) {  // out of reach: what a clear leaves
          const size_t a = static_cast<size_t>(j) * n + bi * B;
          const size_t b = static_cast<size_t>(j) * n + std::min(n, bi * B + B);
          std::fill(gap_m + a, gap_m + b, kInf);
          std::fill(coverage + a, coverage + b, 0.0);
        }
        continue;
      }
      // A run of consecutive blocks within reach: one branch-free loop.
      int bend = bi;
      while (bend + 1 <= reach.i1 && block_lb[bj * nb + bend + 1] <= cull) ++bend;
      const int i0 = bi * B, i1 = std::min(n, bend * B + B);
      bi = bend;
      const size_t base = static_cast<size_t>(j) * n;
      const double* z = skin_z.data() + base;
      double* gp = gap_m + base;
      double* cp = coverage + base;
      const RowSpan row{r7 * v, r8, top, cull, oyj, area};
      if (overwrite) {
        if (plane)
          AlignedRow<true, true>(row, i0, i1, z, qz0, ox, mean, gp, cp, took);
        else
          AlignedRow<false, true>(row, i0, i1, z, qz0, ox, mean, gp, cp, took);
      } else {
        if (plane)
          AlignedRow<true, false>(row, i0, i1, z, qz0, ox, mean, gp, cp, took);
        else
          AlignedRow<false, false>(row, i0, i1, z, qz0, ox, mean, gp, cp, took);
      }
      int a = i0, b = i1 - 1;
      while (a <= b && took[a] == 0.0) ++a;
      while (b >= a && took[b] == 0.0) --b;
      if (a <= b) {
        lo = std::min(lo, a);
        hi = std::max(hi, b);
      }
      if (!per_cell) continue;  // every column's mean is known
      // Cells whose texture mean depends on the row too (2D height fields,
      // footprints clipped to a sliver at the texture's edge).
      for (int i = i0; i < i1; ++i) {
        const double zi = z[i];
        if (!(std::abs(zi) < kInf) || mean[i] == mean[i]) continue;
        const double qz = tz + r6 * u[i] + r7 * v + r8 * zi;
        if (qz - top > cull) continue;
        const double cov = area > 0 ? ox[i] * oyj / area : 0.0;
        if (cov <= 0.0) continue;
        const double gap = qz - HeightFieldBoxMean(s, x0[i], x1[i], y0[j], y1[j]);
        if (gap < gp[i]) {
          gp[i] = gap;
          cp[i] = cov;
          lo = std::min(lo, i);
          hi = std::max(hi, i);
        }
      }
    }
    if (hi >= 0) {
      ext->cells.AddRow(lo, hi, j);
      ext->wrote = true;
      if (extrema) {  // the row is still in L1
        const size_t base = static_cast<size_t>(j) * n;
        AddExtrema(gap_m + base, coverage + base, lo, hi + 1, extrema);
        spans->row.push_back(j);
        spans->begin.push_back(lo);
        spans->end.push_back(hi + 1);
      }
    }
  }
  return true;
}

}  // namespace surface_detail
}  // namespace mjtouch
