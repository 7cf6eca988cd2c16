#include "pipeline/elastic/grid_cycle.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/simd.h"
#include "pipeline/elastic/warm_start.h"

namespace mjtouch {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Relative change of the indentation depth beyond which an older grid's
// solution is not averaged (steady sliding changes it by far less per cycle).
constexpr double kCycleDepthChange = 0.05;
// The largest tolerance the scaled one reaches (the attribute's own bound).
constexpr double kMaxCycleTolerance = 0.1;

// Where an offset grid's cells go on the taxel grid, per axis: cell i,
// centred at taxel centre i - 1 + a, goes to taxel cells i - 1 + shift
// (weight 1 - w) and i + shift (weight w): whole to the nearest cell
// (w = 0), in halves at a tie (w = 1/2). A grid's field is thus moved by
// under half a cell, and the moves of the offsets k / N sum to zero, so the
// average keeps the total and first moment. Why not cloud-in-cell (w = a -
// shift on every grid, exact moments per grid): it is a linear
// interpolation, and its average over the offsets is a low-pass (mean of
// (1 - a) cos(a theta) + a cos((1 - a) theta), theta in radians per cell:
// 0.88 at five cells a period); the nearest cell's is, at N = 4,
// (1 + 2 cos(theta / 4) + cos(theta / 2)) / 4: 0.93 there.
struct Deposit {
  int shift;
  double w;
};

Deposit DepositOf(const TaxelGrid& offset_grid, const TaxelGrid& grid) {
  // centre of offset cell i = taxel centre (i - 1) + a cells
  const double a = (offset_grid.Centre(0) - grid.Centre(0)) / grid.pitch_m + 1.0;
  // (k / N = 1/2 gives a = 1 - 2e-16 in floating point: a whole cell)
  const double nearest = std::round(a);
  if (std::abs(a - nearest) < 0.5 - 1e-9) return Deposit{static_cast<int>(nearest), 0.0};
  return Deposit{static_cast<int>(std::floor(a + 1e-9)), 0.5};
}

// One grid's share of the average: a weighted sum of up to two of its
// solutions (a pressure field on a box: a double field, or a history block's
// floats).
struct DepositTerm {
  const double* field = nullptr;  // the grid's full field, or
  const HistoryBlock* block = nullptr;
  CellBox box;
  double scale = 0.0;
};

// Adds the weighted sum of terms[0 .. nterms) (a grid's cells) onto the taxel
// field (DepositOf's weights): separably, row by row over each row's positive
// cells; extends *cells by the taxels they reach. row, row_f: scratch.
MJTOUCH_TARGET_CLONES void AddDeposit(const TaxelGrid& g, const DepositTerm* terms, int nterms,
                                      const Deposit& d, const TaxelGrid& grid,
                                      std::vector<double>* row, std::vector<float>* row_f,
                                      std::vector<double>* out, CellBounds* cells) {
  const int n = grid.n;
  CellBounds all;
  for (int t = 0; t < nterms; ++t) {
    const CellBox& bx = terms[t].box;
    if (bx.empty()) continue;
    all.AddRow(bx.i0, bx.i0 + bx.nx - 1, bx.j0);
    all.AddRow(bx.i0, bx.i0 + bx.nx - 1, bx.j0 + bx.ny - 1);
  }
  if (all.empty()) return;
  const int i0 = all.i0, i1 = all.i1 + 1;
  row->resize(static_cast<size_t>(g.n));
  row_f->resize(static_cast<size_t>(g.n));
  double* v = row->data();
  const double wt[2] = {1.0 - d.w, d.w};
  for (int j = all.j0; j <= all.j1; ++j) {
    std::fill(v + i0, v + i1, 0.0);
    for (int t = 0; t < nterms; ++t) {
      const CellBox& bx = terms[t].box;
      if (bx.empty() || j < bx.j0 || j >= bx.j0 + bx.ny) continue;
      const size_t k = static_cast<size_t>(j) * g.n + bx.i0;
      const double sc = terms[t].scale;
      if (terms[t].field) {
        const double* p = terms[t].field + k;
        for (int i = 0; i < bx.nx; ++i) v[bx.i0 + i] += sc * p[i];
      } else {
        float* f = row_f->data();
        terms[t].block->p_row(k, bx.nx, f);
        for (int i = 0; i < bx.nx; ++i) v[bx.i0 + i] += sc * static_cast<double>(f[i]);
      }
    }
    int lo = i0, hi = i1 - 1;
    while (lo <= hi && !(v[lo] > 0.0)) ++lo;
    if (lo > hi) continue;
    while (!(v[hi] > 0.0)) --hi;
    for (int b = 0; b < 2; ++b) {
      const int tj = j - 1 + d.shift + b;
      if (tj < 0 || tj >= n || wt[b] == 0.0) continue;
      double* o = out->data() + static_cast<size_t>(tj) * n;
      for (int a = 0; a < 2; ++a) {
        if (wt[a] == 0.0) continue;
        const double wa = wt[b] * wt[a];
        // taxel ti = i - 1 + shift + a
        const int off = d.shift - 1 + a;
        const int ia = std::max(lo, -off), ib = std::min(hi, n - 1 - off);
        if (ia > ib) continue;
        double* oo = o + off;
        for (int i = ia; i <= ib; ++i) oo[i] += wa * v[i];
        cells->AddRow(ia + off, ib + off, tj);
      }
    }
  }
}

}  // namespace

int CycleLength(int n_grids, double dt_s) {
  int length = n_grids;
  if (dt_s > 0.0)
    while (length > 1 && (n_grids % length != 0 || length * dt_s > kMaxCyclePeriodS * (1 + 1e-9)))
      --length;
  return length;
}

bool CycleTraction(const CycleGrids& cg, int slot, int length, const TaxelGrid& grid,
                   const Pose& pad_pose, const std::vector<CounterSurface>& surfaces,
                   double force_n, bool warm, double depth_prev_m,
                   const ElasticSolveOptions& options, bool fast_paths, HistoryBlock* ring,
                   GridShiftWork* w, TractionField* field, double* depth_m) {
  const int N = static_cast<int>(cg.grids.size());
  // the grid solved b steps back
  auto grid_at = [&](int b) {
    const int phase = ((slot - b) % length + length) % length;
    return (phase * (N / length) + N / 2) % N;
  };
  const ShiftedGrid& sg = cg.grids[grid_at(0)];
  const TaxelGrid& g = sg.grid;
  // The warm start: this grid's last solution (N steps back), with its
  // stored K p (warm_start.h); before it has one, the last step's grid's (a
  // sub-cell offset away). The contact set changes between a grid's turns
  // are what its solve pays for, and no other grid's solution predicts them:
  // on the sliding scene, extrapolating from its solutions N and 2 N steps
  // back took 8.8 CG iterations (8.9 without), the last step's grid's
  // solution resampled to this grid 13.2, and this grid's last plus the
  // change the last step's grid saw over N steps 10.8.
  auto valid = [&](int b) { return ring[b].slots[kHsValid] > 0.0; };
  WarmTerm terms[1];
  int nterms = 0;
  const int L = length;
  if (valid(L)) {
    terms[nterms++] = WarmTerm{&ring[L], 1.0};
  } else if (L > 1 && valid(1)) {
    terms[nterms++] = WarmTerm{&ring[1], 1.0};
  }
  // Each grid stops at L times the tolerance: its solution enters the
  // average with weight 1 / L, and from a start L steps old the stopping
  // test leaves less error than from the single grid's extrapolated one
  // (receptor stress increments on the default slide, against a solve to
  // 1e-6: 1.5% at L = 4 and 4e-4, 0.4% at 1e-4; the taxel grid alone 2.6%
  // at 1e-4).
  ElasticSolveOptions cycle_options = options;
  cycle_options.tolerance = std::min(options.tolerance * L, kMaxCycleTolerance);
  const double cull = warm ? CullLevel(depth_prev_m) : kInf;
  bool touching = false;
  CellBox sbox, u_region;
  double gmin = 0.0;
  for (int pass = 0; pass < 2 && !touching; ++pass) {
    if (pass == 1 && !std::isfinite(cull)) break;
    CellBox rbox;
    RenderRequest request{g, sg.skin_z, pad_pose, surfaces, pass == 0 ? cull : kInf, &sg.blocks};
    request.fast_paths = fast_paths;
    RenderOutput out{&w->gap, &w->coverage, &rbox};
    // (the grids share the buffers: all have n + 1 cells)
    out.written = fast_paths ? &w->gap_written : nullptr;
    out.scratch = &w->render_scratch;
    const double level = RenderGap(request, out);
    gmin = rbox.empty() ? kInf : MinGap(g, rbox, w->gap, w->coverage);
    if (!std::isfinite(gmin)) return false;
    sbox = rbox;  // cold: uniform from the whole rendered box
    if (nterms == 0) w->pressure.assign(g.Size(), 0.0);
    touching = SolveElasticWarmFrom(g, *sg.elastic, rbox, w->coverage, terms, nterms, true, force_n,
                                    cycle_options, &w->gap, &w->pressure, &w->elastic, &w->stats,
                                    &sbox, &u_region);
    if (!touching) return false;
    if (pass == 0 && w->stats.approach_m >= level) touching = false;  // render all, solve again
  }
  if (!touching) return false;
  *depth_m = w->stats.approach_m - gmin;
  StoreElasticHistory(g, w->pressure, sbox, u_region, w->elastic.check_u, *depth_m, &ring[0]);
  // The average of every cycling grid's solution at one common time,
  // L - 1 steps back: the grid solved a steps back interpolated linearly
  // between its last two solutions (a and a + L steps back; weights
  // (L - 1 - a) / L on the older). Equal times let the grids' errors cancel;
  // each grid's latest solution held instead (ages 0 .. L - 1) leaves them
  // modulated at the cycle's frequency 1 / (L dt), and extrapolating to
  // the present amplifies the solutions' jumps as the contact set changes.
  // Solutions of another contact (the indentation depth changed by more
  // than kCycleDepthChange since, e.g. a jump) are left out until their
  // grids' turns come: the average then holds fewer grids for a cycle.
  auto current = [&](int b) {
    return valid(b) &&
           std::abs(ring[b].slots[kHsDepth] - *depth_m) <= kCycleDepthChange * (*depth_m);
  };
  int count = 0;
  for (int b = 0; b < L; ++b) count += current(b);
  const double scale = 1.0 / count;
  CellBounds cells;
  for (int b = 0; b < L; ++b) {
    if (!current(b)) continue;
    const ShiftedGrid& gb = cg.grids[grid_at(b)];
    const Deposit d = DepositOf(gb.grid, grid);
    // weight of the older solution (b + L steps back), of the newer
    const double f = current(b + L) ? static_cast<double>(L - 1 - b) / L : 0.0;
    DepositTerm dt[2];
    int nd = 0;
    if (f < 1.0) {
      dt[nd].scale = scale * (1.0 - f);
      if (b == 0) {
        dt[nd].field = w->pressure.data();
        dt[nd].box = sbox;
      } else {
        dt[nd].block = &ring[b];
        dt[nd].box = ring[b].p_box();
      }
      ++nd;
    }
    if (f > 0.0) {
      dt[nd].block = &ring[b + L];
      dt[nd].box = ring[b + L].p_box();
      dt[nd].scale = scale * f;
      ++nd;
    }
    AddDeposit(gb.grid, dt, nd, d, grid, &w->deposit_row, &w->deposit_row_f, &field->pressure_pa,
               &cells);
  }
  field->box = cells.Box();
  return NormalizeLoad(grid, force_n, field);
}

}  // namespace mjtouch
