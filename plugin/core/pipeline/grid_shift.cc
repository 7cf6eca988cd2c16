#include "pipeline/grid_shift.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mjtouch {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Smallest gap over covered cells of box (+inf if none).
double MinCoveredGap(const TaxelGrid& g, const CellBox& box, const std::vector<double>& gap,
                     const std::vector<double>& cov) {
  double m = kInf;
  for (int j = box.j0; j < box.j0 + box.ny; ++j)
    for (int i = box.i0; i < box.i0 + box.nx; ++i) {
      const size_t k = static_cast<size_t>(j) * g.n + i;
      if (cov[k] > 0.0) m = std::min(m, gap[k]);
    }
  return m;
}

constexpr int kMarginCells = 3;

CellBox Intersect(const CellBox& a, const CellBox& b) {
  const int i0 = std::max(a.i0, b.i0), j0 = std::max(a.j0, b.j0);
  const int i1 = std::min(a.i0 + a.nx, b.i0 + b.nx), j1 = std::min(a.j0 + a.ny, b.j0 + b.ny);
  return CellBox{i0, j0, std::max(0, i1 - i0), std::max(0, j1 - j0)};
}

// True if some rendered cell (rbox) outside sbox could touch under the
// pressure solved on sbox: g0 + K p < approach. Cells above approach + the
// skin's largest lift under the whole load pass without the operator; the
// rest get K p from one application over rbox.
bool ContactEscapes(const ShiftedGrid& sg, const CellBox& rbox, const CellBox& sbox,
                    double force_n, ApplyPrecision precision, GridShiftWork* w) {
  const TaxelGrid& g = sg.grid;
  const double approach = w->stats.approach_m;
  const double lift = sg.elastic->max_lift_m_per_pa() * force_n / g.Area();
  auto inside = [&](int i, int j) {
    return i >= sbox.i0 && i < sbox.i0 + sbox.nx && j >= sbox.j0 && j < sbox.j0 + sbox.ny;
  };
  bool any = false;
  for (int j = rbox.j0; j < rbox.j0 + rbox.ny && !any; ++j)
    for (int i = rbox.i0; i < rbox.i0 + rbox.nx; ++i)
      if (!inside(i, j) && w->gap[static_cast<size_t>(j) * g.n + i] <= approach + lift) {
        any = true;
        break;
      }
  if (!any) return false;
  const int bx = rbox.nx, by = rbox.ny;
  std::vector<double>& pin = w->elastic.check_p;
  std::vector<double>& u = w->elastic.check_u;
  pin.assign(static_cast<size_t>(bx) * by, 0.0);
  u.resize(pin.size());
  for (int j = sbox.j0; j < sbox.j0 + sbox.ny; ++j)
    for (int i = sbox.i0; i < sbox.i0 + sbox.nx; ++i)
      pin[static_cast<size_t>(j - rbox.j0) * bx + (i - rbox.i0)] =
          w->pressure[static_cast<size_t>(j) * g.n + i];
  const SurfaceCompliance& K = sg.elastic->compliance();
  K.Apply(*K.SpectrumFor(bx, by), pin.data(), bx, by, u.data(), &w->elastic.fft, precision);
  for (int j = rbox.j0; j < rbox.j0 + rbox.ny; ++j)
    for (int i = rbox.i0; i < rbox.i0 + rbox.nx; ++i) {
      if (inside(i, j)) continue;
      const double gap = w->gap[static_cast<size_t>(j) * g.n + i];
      if (gap <= approach + lift &&
          !(gap + u[static_cast<size_t>(j - rbox.j0) * bx + (i - rbox.i0)] >= approach))
        return true;
    }
  return false;
}

}  // namespace

bool AverageWithShiftedGrid(const ShiftedGrid& sg, const TaxelGrid& grid, const Pose& pad_pose,
                            const std::vector<CounterSurface>& surfaces, double force_n,
                            double depth_m, double tolerance, int max_iterations,
                            ElasticMethod method, ApplyPrecision precision, bool fast_paths,
                            GridShiftWork* w, TractionField* field) {
  const TaxelGrid& g = sg.grid;  // g.n == grid.n + 1
  const int n = grid.n;
  w->main_pressure = field->pressure_pa;
  w->main_box = field->box;
  // The same cull rule as the taxel grid's (skin_traction.cc), from this
  // step's indentation depth.
  const double cull = 1.5 * depth_m + 20e-6;
  const CellBox& mb = w->main_box;
  bool touching = false;
  for (int pass = 0; pass < 2 && !touching; ++pass) {
    CellBox rbox;
    const double level = RenderGap(g, sg.skin_z, pad_pose, surfaces, pass == 0 ? cull : kInf,
                                   &w->gap, &w->coverage, true, &sg.blocks, &rbox, fast_paths);
    if (rbox.empty() || !std::isfinite(MinCoveredGap(g, rbox, w->gap, w->coverage)))
      return true;  // nothing under the shifted grid: keep the taxel grid's solution
    for (int j = rbox.j0; j < rbox.j0 + rbox.ny; ++j)
      for (int i = rbox.i0; i < rbox.i0 + rbox.nx; ++i) {
        const size_t k = static_cast<size_t>(j) * g.n + i;
        if (!(w->coverage[k] > 0.0)) w->gap[k] = kInf;
      }
    // Warm start: the taxel grid's solution moved onto the shifted cells
    // (shifted cell (i, j) overlaps taxel cells i - 1..i, j - 1..j).
    w->pressure.assign(g.Size(), 0.0);
    for (int j = std::max(rbox.j0, mb.j0); j < std::min(rbox.j0 + rbox.ny, mb.j0 + mb.ny + 1); ++j)
      for (int i = std::max(rbox.i0, mb.i0); i < std::min(rbox.i0 + rbox.nx, mb.i0 + mb.nx + 1);
           ++i) {
        double s = 0.0;
        for (int dj = -1; dj <= 0; ++dj)
          for (int di = -1; di <= 0; ++di) {
            const int a = i + di, b = j + dj;
            if (a >= 0 && a < n && b >= 0 && b < n)
              s += w->main_pressure[static_cast<size_t>(b) * n + a];
          }
        w->pressure[static_cast<size_t>(j) * g.n + i] = 0.25 * s;
      }
    // First on the taxel grid's solve box moved onto the shifted cells
    // (taxel cells i0..i1 overlap shifted cells i0..i1 + 1), kMarginCells
    // wider; if a rendered cell outside it could touch (ContactEscapes),
    // again on every rendered cell.
    const CellBox sbox = Intersect(rbox, CellBox{mb.i0 - kMarginCells, mb.j0 - kMarginCells,
                                                 mb.nx + 1 + 2 * kMarginCells,
                                                 mb.ny + 1 + 2 * kMarginCells});
    w->guess = w->pressure;
    touching = !sbox.empty() &&
               sg.elastic->Solve(w->gap, sbox, force_n, tolerance, max_iterations, &w->pressure,
                                 &w->elastic, &w->stats, method, precision);
    if (!touching || ContactEscapes(sg, rbox, sbox, force_n, precision, w)) {
      w->pressure = w->guess;
      touching = sg.elastic->Solve(w->gap, rbox, force_n, tolerance, max_iterations,
                                   &w->pressure, &w->elastic, &w->stats, method, precision);
    }
    if (!touching) return false;
    if (pass == 0 && w->stats.approach_m >= level) touching = false;  // render all, solve again
  }
  // Deposit (taxel cell (i, j) <- shifted cells i..i+1, j..j+1, a quarter
  // each) and average on the grown box.
  const int i0 = std::max(0, mb.i0 - 1), j0 = std::max(0, mb.j0 - 1);
  const int i1 = std::min(n, mb.i0 + mb.nx + 1), j1 = std::min(n, mb.j0 + mb.ny + 1);
  // The shifted solution's support decides the box too.
  int si0 = g.n, si1 = -1, sj0 = g.n, sj1 = -1;
  for (int j = 0; j < g.n; ++j)
    for (int i = 0; i < g.n; ++i)
      if (w->pressure[static_cast<size_t>(j) * g.n + i] > 0.0) {
        si0 = std::min(si0, i);
        si1 = std::max(si1, i);
        sj0 = std::min(sj0, j);
        sj1 = std::max(sj1, j);
      }
  const int bi0 = std::max(0, std::min(i0, si0 - 1)), bj0 = std::max(0, std::min(j0, sj0 - 1));
  const int bi1 = std::min(n, std::max(i1, si1 + 1)), bj1 = std::min(n, std::max(j1, sj1 + 1));
  for (int j = bj0; j < bj1; ++j)
    for (int i = bi0; i < bi1; ++i) {
      const double* s0 = w->pressure.data() + static_cast<size_t>(j) * g.n + i;
      const double dep = 0.25 * (s0[0] + s0[1] + s0[g.n] + s0[g.n + 1]);
      const size_t k = static_cast<size_t>(j) * n + i;
      field->pressure_pa[k] = 0.5 * (w->main_pressure[k] + dep);
    }
  field->box = CellBox{bi0, bj0, bi1 - bi0, bj1 - bj0};
  // The shifted cells on the grid's rim lose their outer halves.
  return NormalizeLoad(grid, force_n, field);
}

}  // namespace mjtouch
