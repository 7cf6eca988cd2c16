#include "pipeline/elastic/grid_shift.h"

#include "pipeline/elastic/warm_start.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mjtouch {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

bool AverageWithShiftedGrid(const ShiftedGrid& sg, const TaxelGrid& grid, const Pose& pad_pose,
                            const std::vector<CounterSurface>& surfaces, double force_n,
                            double depth_m, const ElasticSolveOptions& options, bool fast_paths,
                            HistoryBlock* history, GridShiftWork* w, TractionField* field) {
  const TaxelGrid& g = sg.grid;  // g.n == grid.n + 1
  const int n = grid.n;
  const CellBox mb = field->box;  // the taxel grid's solution's
  // The taxel grid's cull rule, from this step's indentation depth.
  const double cull = CullLevel(depth_m);
  bool touching = false;
  CellBox sbox, u_region;  // the final solve box, the check's K p region
  for (int pass = 0; pass < 2 && !touching; ++pass) {
    CellBox rbox;
    RenderRequest request{g, sg.skin_z, pad_pose, surfaces, pass == 0 ? cull : kInf, &sg.blocks};
    request.fast_paths = fast_paths;
    RenderOutput out{&w->gap, &w->coverage, &rbox};
    out.scratch = &w->render_scratch;
    const double level = RenderGap(request, out);
    if (rbox.empty() || !std::isfinite(MinGap(g, rbox, w->gap, w->coverage)))
      return true;  // nothing under the shifted grid: keep the taxel grid's solution
    // Warm-started from the shifted grid's own history as the taxel grid's
    // solve; without a last step, from the taxel grid's solution moved onto
    // the shifted cells (shifted cell (i, j) overlaps taxel cells
    // i - 1..i, j - 1..j).
    sbox = rbox;
    if (!HasWarmStart(history)) {
      w->pressure.assign(g.Size(), 0.0);
      for (int j = std::max(rbox.j0, mb.j0); j < std::min(rbox.j0 + rbox.ny, mb.j0 + mb.ny + 1);
           ++j)
        for (int i = std::max(rbox.i0, mb.i0); i < std::min(rbox.i0 + rbox.nx, mb.i0 + mb.nx + 1);
             ++i) {
          double s = 0.0;
          for (int dj = -1; dj <= 0; ++dj)
            for (int di = -1; di <= 0; ++di) {
              const int a = i + di, b = j + dj;
              if (a >= 0 && a < n && b >= 0 && b < n)
                s += field->pressure_pa[static_cast<size_t>(b) * n + a];
            }
          w->pressure[static_cast<size_t>(j) * g.n + i] = 0.25 * s;
        }
      // the taxel grid's solve box moved onto the shifted cells (taxel
      // cells i0..i1 overlap shifted cells i0..i1 + 1), kBoxMarginCells wider
      sbox = GrowBox(rbox, mb.i0, mb.i0 + mb.nx, mb.j0, mb.j0 + mb.ny);
      if (sbox.empty()) sbox = rbox;
    }
    touching = SolveElasticWarm(g, *sg.elastic, rbox, w->coverage, history, force_n, options,
                                &w->gap, &w->pressure, &w->elastic, &w->stats, &sbox, &u_region);
    if (!touching) return false;
    if (pass == 0 && w->stats.approach_m >= level) touching = false;  // render all, solve again
  }
  // this step's shifted solution and its K p (the check's); the taxel
  // grid's history holds the depth
  if (history)
    StoreElasticHistory(g, w->pressure, sbox, u_region, w->elastic.check_u, 0.0, &history[0]);
  // Deposit (taxel cell (i, j) <- shifted cells i..i+1, j..j+1, a quarter
  // each) and average on the grown box.
  const int i0 = std::max(0, mb.i0 - 1), j0 = std::max(0, mb.j0 - 1);
  const int i1 = std::min(n, mb.i0 + mb.nx + 1), j1 = std::min(n, mb.j0 + mb.ny + 1);
  // The shifted solution's support decides the box too (zero outside sbox).
  CellBounds s;
  for (int j = sbox.j0; j < sbox.j0 + sbox.ny; ++j)
    for (int i = sbox.i0; i < sbox.i0 + sbox.nx; ++i)
      if (w->pressure[static_cast<size_t>(j) * g.n + i] > 0.0) s.Add(i, j);
  int bi0 = i0, bj0 = j0, bi1 = i1, bj1 = j1;
  if (!s.empty()) {
    bi0 = std::max(0, std::min(i0, s.i0 - 1));
    bj0 = std::max(0, std::min(j0, s.j0 - 1));
    bi1 = std::min(n, std::max(i1, s.i1 + 1));
    bj1 = std::min(n, std::max(j1, s.j1 + 1));
  }
  for (int j = bj0; j < bj1; ++j)
    for (int i = bi0; i < bi1; ++i) {
      const double* s0 = w->pressure.data() + static_cast<size_t>(j) * g.n + i;
      const double dep = 0.25 * (s0[0] + s0[1] + s0[g.n] + s0[g.n + 1]);
      const size_t k = static_cast<size_t>(j) * n + i;
      field->pressure_pa[k] = 0.5 * (field->pressure_pa[k] + dep);
    }
  field->box = CellBox{bi0, bj0, bi1 - bi0, bj1 - bj0};
  // The shifted cells on the grid's rim lose their outer halves.
  return NormalizeLoad(grid, force_n, field);
}

}  // namespace mjtouch
