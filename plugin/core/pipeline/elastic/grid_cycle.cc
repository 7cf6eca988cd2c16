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
  const double a = (offset_grid.Centre(0) - grid.Centre(0)) / grid.pitch_m + 1.0;
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
      if (v == 0.0) continue;
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

CellBox Union(const CellBox& a, const CellBox& b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  const int i0 = std::min(a.i0, b.i0), j0 = std::min(a.j0, b.j0);
  const int i1 = std::max(a.i0 + a.nx, b.i0 + b.nx), j1 = std::max(a.j0 + a.ny, b.j0 + b.ny);
  return CellBox{i0, j0, i1 - i0, j1 - j0};
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
  // The average of every cycling grid's latest solution, each carried to
  // this time by linear extrapolation from its last two (the grid solved a
  // steps back: (1 + a / L) p(a) - (a / L) p(a + L)); held values would
  // leave what the grids' errors cancel only at equal times to be modulated
  // at the cycle's frequency.
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
    if (b == 0) {
      const double* p = w->pressure.data();
      AddDeposit(
          gb.grid, sbox, d, scale, [p](size_t c) { return p[c]; }, grid, &field->pressure_pa,
          &cells);
      continue;
    }
    const HistoryBlock& h = ring[b];
    const CellBox hb = h.p_box();
    if (!current(b + L)) {
      AddDeposit(
          gb.grid, hb, d, scale, [&h](size_t c) { return double(h.p(c)); }, grid,
          &field->pressure_pa, &cells);
      continue;
    }
    const HistoryBlock& o = ring[b + L];
    const CellBox ob = o.p_box();
    const double f = static_cast<double>(b) / L;
    const int n1 = gb.grid.n;
    auto inside = [n1](const CellBox& x, size_t c) {
      const int i = static_cast<int>(c % n1), j = static_cast<int>(c / n1);
      return i >= x.i0 && i < x.i0 + x.nx && j >= x.j0 && j < x.j0 + x.ny;
    };
    AddDeposit(
        gb.grid, Union(hb, ob), d, scale,
        [&](size_t c) {
          const double a = inside(hb, c) ? double(h.p(c)) : 0.0;
          const double z = inside(ob, c) ? double(o.p(c)) : 0.0;
          return (1.0 + f) * a - f * z;
        },
        grid, &field->pressure_pa, &cells);
  }
  // extrapolation may leave cells leaving the contact below zero
  const CellBox fb = cells.Box();
  for (int j = fb.j0; j < fb.j0 + fb.ny; ++j)
    for (int i = fb.i0; i < fb.i0 + fb.nx; ++i) {
      double& v = field->pressure_pa[static_cast<size_t>(j) * grid.n + i];
      v = std::max(v, 0.0);
    }
  field->box = cells.Box();
  return NormalizeLoad(grid, force_n, field);
}

}  // namespace mjtouch
