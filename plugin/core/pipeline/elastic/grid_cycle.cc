#include "pipeline/elastic/grid_cycle.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pipeline/elastic/warm_start.h"

namespace mjtouch {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Relative change of the indentation depth beyond which an older grid's
// solution is not averaged (steady sliding changes it by far less per cycle).
constexpr double kCycleDepthChange = 0.05;

// Cloud-in-cell weights of an offset grid's cells on the taxel grid, per
// axis: cell i (centre at taxel corner i plus `frac` - 1/2 cells) goes to
// taxel cells i - 1 + shift (weight 1 - w) and i + shift (weight w).
struct Deposit {
  int shift;
  double w;
};

Deposit DepositOf(const TaxelGrid& offset_grid, const TaxelGrid& grid) {
  // centre of offset cell i = taxel centre (i - 1) + a cells
  double a = (offset_grid.Centre(0) - grid.Centre(0)) / grid.pitch_m + 1.0;
  // A whole-cell offset (k / N = 1/2 gives a = 1 - 2e-16 in floating point)
  // deposits on one cell, not on two with a round-off weight on the second:
  // that weight would give cells pressures of 1e-16 of the peak, which count
  // as loaded (and, under shear="partial", as slipping).
  if (std::abs(a - std::round(a)) < 1e-9) a = std::round(a);
  const int shift = static_cast<int>(std::floor(a));
  return Deposit{shift, a - shift};
}

// Adds scale * (a grid's pressure on box, p(k) for grid cell index k) onto
// the taxel field, cloud-in-cell; extends *cells.
template <typename P>
void AddDeposit(const TaxelGrid& g, const CellBox& box, const Deposit& d, double scale, P p,
                const TaxelGrid& grid, std::vector<double>* out, CellBounds* cells) {
  const int n = grid.n;
  const double w1 = d.w, w0 = 1.0 - d.w;
  const double wy[2] = {w0, w1}, wx[2] = {w0, w1};
  for (int j = box.j0; j < box.j0 + box.ny; ++j)
    for (int i = box.i0; i < box.i0 + box.nx; ++i) {
      const double v = p(static_cast<size_t>(j) * g.n + i);
      if (!(v > 0.0)) continue;
      for (int b = 0; b < 2; ++b) {
        const int tj = j - 1 + d.shift + b;
        if (tj < 0 || tj >= n || wy[b] == 0.0) continue;
        for (int a = 0; a < 2; ++a) {
          const int ti = i - 1 + d.shift + a;
          if (ti < 0 || ti >= n || wx[a] == 0.0) continue;
          (*out)[static_cast<size_t>(tj) * n + ti] += scale * wy[b] * wx[a] * v;
          cells->Add(ti, tj);
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
  // The warm start: this grid's last two solutions (N and 2 N steps back)
  // extrapolated, with their stored K p (warm_start.h); before it has them,
  // its last, or the last step's grid's (a sub-cell offset away).
  // (Adding the change the last step's grid saw over N steps to this grid's
  // last solution took more iterations on the sliding scene: 10.8 vs 8.7.)
  auto valid = [&](int b) { return ring[b].slots[kHsValid] > 0.0; };
  WarmTerm terms[2];
  int nterms = 0;
  const int L = length;
  if (options.method == ElasticMethod::kPreconditioned && valid(L) && valid(2 * L)) {
    terms[nterms++] = WarmTerm{&ring[L], 2.0};
    terms[nterms++] = WarmTerm{&ring[2 * L], -1.0};
  } else if (valid(L)) {
    terms[nterms++] = WarmTerm{&ring[L], 1.0};
  } else if (L > 1 && valid(1)) {
    terms[nterms++] = WarmTerm{&ring[1], 1.0};
  }
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
    out.scratch = &w->render_scratch;
    const double level = RenderGap(request, out);
    gmin = rbox.empty() ? kInf : MinGap(g, rbox, w->gap, w->coverage);
    if (!std::isfinite(gmin)) return false;
    sbox = rbox;  // cold: uniform from the whole rendered box
    if (nterms == 0) w->pressure.assign(g.Size(), 0.0);
    touching =
        SolveElasticWarmFrom(g, *sg.elastic, rbox, w->coverage, terms, nterms, force_n, options,
                             &w->gap, &w->pressure, &w->elastic, &w->stats, &sbox, &u_region);
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
    if (f < 1.0) {
      const double sc = scale * (1.0 - f);
      if (b == 0) {
        const double* p = w->pressure.data();
        AddDeposit(
            gb.grid, sbox, d, sc, [p](size_t c) { return p[c]; }, grid, &field->pressure_pa,
            &cells);
      } else {
        const HistoryBlock& h = ring[b];
        AddDeposit(
            gb.grid, h.p_box(), d, sc, [&h](size_t c) { return double(h.p(c)); }, grid,
            &field->pressure_pa, &cells);
      }
    }
    if (f > 0.0) {
      const HistoryBlock& o = ring[b + L];
      AddDeposit(
          gb.grid, o.p_box(), d, scale * f, [&o](size_t c) { return double(o.p(c)); }, grid,
          &field->pressure_pa, &cells);
    }
  }
  field->box = cells.Box();
  return NormalizeLoad(grid, force_n, field);
}

}  // namespace mjtouch
