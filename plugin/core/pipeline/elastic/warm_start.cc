// The `elastic` contact's solve sequence for one step (warm_start.h): the
// warm start from the pressure history, the solve on a box grown until no
// rendered cell outside it can touch, and the history write.
#include "pipeline/elastic/warm_start.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mjtouch {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Cells the elastic solve box extends beyond the last step's contact (a
// sliding contact moves well under a cell per step).
constexpr int kBoxMarginCells = 3;
// Solves on a grown box before the whole rendered box.
constexpr int kBoxAttempts = 3;

}  // namespace

// Cells [i0, i1] x [j0, j1] widened by kBoxMarginCells, clipped to box.
CellBox GrowBox(const CellBox& box, int i0, int i1, int j0, int j1) {
  i0 = std::max(box.i0, i0 - kBoxMarginCells);
  j0 = std::max(box.j0, j0 - kBoxMarginCells);
  i1 = std::min(box.i0 + box.nx - 1, i1 + kBoxMarginCells);
  j1 = std::min(box.j0 + box.ny - 1, j1 + kBoxMarginCells);
  return CellBox{i0, j0, i1 - i0 + 1, j1 - j0 + 1};
}

// Smallest gap over the covered cells of the box (+inf if none).
double MinGap(const TaxelGrid& grid, const CellBox& box, const std::vector<double>& gap,
              const std::vector<double>& cov) {
  // Four running minima (the minimum does not depend on the order).
  double m[4] = {kInf, kInf, kInf, kInf};
  for (int j = box.j0; j < box.j0 + box.ny; ++j) {
    const double* g = gap.data() + static_cast<size_t>(j) * grid.n;
    const double* c = cov.data() + static_cast<size_t>(j) * grid.n;
    int i = box.i0;
    for (; i + 4 <= box.i0 + box.nx; i += 4)
      for (int k = 0; k < 4; ++k)
        if (c[i + k] > 0.0) m[k] = std::min(m[k], g[i + k]);
    for (; i < box.i0 + box.nx; ++i)
      if (c[i] > 0.0) m[0] = std::min(m[0], g[i]);
  }
  return std::min(std::min(m[0], m[1]), std::min(m[2], m[3]));
}

namespace {

// True if no rendered cell (box) outside `inner` can touch under the
// pressure solved on `inner` (zero elsewhere): g0 + K p >= approach there.
// Cells with g0 > approach + lift (lift: a bound on the skin's upward bulge)
// pass without the operator; the rest get u from one application on their
// bounding box. If some cell fails, *grown is the bounding box of inner and
// the failing cells, kBoxMarginCells wider (within box). *u_region: the box
// over which w->check_u holds K p (nx = 0: none computed).
// The application is not wasted when every cell passes (it runs on ~every
// solve of the shipped scenes): its K p is the next two steps' warm-start
// displacement (history; ExtrapolatedDisplacement), so skipping it would
// move an application into the next solve and change its rounding.
bool BoxHoldsContact(const TaxelGrid& grid, const SurfaceCompliance& K,
                     const std::vector<double>& gap, const CellBox& box, const CellBox& inner,
                     const std::vector<double>& pressure, double approach_m, double lift_m,
                     const ElasticSolveOptions& opt, ElasticStepWork* w, CellBox* grown,
                     CellBox* u_region) {
  // fn(i, j) for the cells of [ia, ib) x [ja, jb) outside inner (row
  // segments: inner is most of the box).
  auto for_outside = [&](int ia, int ib, int ja, int jb, auto&& fn) {
    for (int j = ja; j < jb; ++j) {
      const bool row_in = j >= inner.j0 && j < inner.j0 + inner.ny;
      const int end = row_in ? std::min(ib, inner.i0) : ib;
      for (int i = ia; i < end; ++i) fn(i, j);
      if (row_in)
        for (int i = std::max(ia, inner.i0 + inner.nx); i < ib; ++i) fn(i, j);
    }
  };
  CellBounds reach(inner);  // inner and the cells outside it within reach
  bool any = false;
  for_outside(box.i0, box.i0 + box.nx, box.j0, box.j0 + box.ny, [&](int i, int j) {
    if (gap[static_cast<size_t>(j) * grid.n + i] <= approach_m + lift_m) {
      any = true;
      reach.Add(i, j);
    }
  });
  *u_region = CellBox{0, 0, 0, 0};
  if (!any) return true;
  const int i0 = reach.i0, i1 = reach.i1, j0 = reach.j0, j1 = reach.j1;
  const int cx = i1 - i0 + 1, cy = j1 - j0 + 1;
  // check_p: the pressure on inner, zero elsewhere (each element written once)
  w->check_p.resize(static_cast<size_t>(cx) * cy);
  w->check_u.resize(w->check_p.size());
  for (int j = j0; j <= j1; ++j) {
    double* to = w->check_p.data() + static_cast<size_t>(j - j0) * cx;
    if (j < inner.j0 || j >= inner.j0 + inner.ny) {
      std::fill(to, to + cx, 0.0);
      continue;
    }
    const double* row = pressure.data() + static_cast<size_t>(j) * grid.n + inner.i0;
    const int a = inner.i0 - i0, b = a + inner.nx;
    std::fill(to, to + a, 0.0);
    std::copy(row, row + inner.nx, to + a);
    std::fill(to + b, to + cx, 0.0);
  }
  // The pressure lives on inner only: offsets from it to the checked cells
  // reach less far than the box's size (a smaller FFT grid), and the
  // columns and rows past it need no transform.
  const int ox = inner.i0 - i0, oy = inner.j0 - j0;
  const auto spec = K.SpectrumForReach(std::max(ox + inner.nx - 1, cx - 1 - ox),
                                       std::max(oy + inner.ny - 1, cy - 1 - oy));
  K.Apply(*spec, w->check_p.data(), cx, cy, w->check_u.data(), &w->solve.fft, opt.precision,
          opt.threads, oy + inner.ny, ox + inner.nx);
  *u_region = CellBox{i0, j0, cx, cy};
  CellBounds fail(inner);  // inner and the cells outside it that would touch
  bool ok = true;
  for_outside(i0, i1 + 1, j0, j1 + 1, [&](int i, int j) {
    const double g = gap[static_cast<size_t>(j) * grid.n + i];
    if (g <= approach_m + lift_m &&
        !(g + w->check_u[static_cast<size_t>(j - j0) * cx + (i - i0)] >= approach_m)) {
      ok = false;
      fail.Add(i, j);
    }
  });
  if (!ok) *grown = GrowBox(box, fail.i0, fail.i1, fail.j0, fail.j1);
  return ok;
}

// The smallest box holding both (either may be empty).
CellBox Union(const CellBox& a, const CellBox& b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  const int i0 = std::min(a.i0, b.i0), j0 = std::min(a.j0, b.j0);
  const int i1 = std::max(a.i0 + a.nx, b.i0 + b.nx), j1 = std::max(a.j0 + a.ny, b.j0 + b.ny);
  return CellBox{i0, j0, i1 - i0, j1 - j0};
}

bool Inside(const CellBox& b, int i, int j) {
  return i >= b.i0 && i < b.i0 + b.nx && j >= b.j0 && j < b.j0 + b.ny;
}

// A history block's pressure at cell (i, j) (zero outside its box).
double HistoryPressure(const HistoryBlock& h, const CellBox& pbox, int i, int j, int n) {
  return Inside(pbox, i, j) ? static_cast<double>(h.p(static_cast<size_t>(j) * n + i)) : 0.0;
}

// One history row's pressure over [i0, i1) into row[i0, i1), as stored
// (float; zero outside its box).
void HistoryRow(const HistoryBlock& h, const CellBox& pbox, int j, int n, int i0, int i1,
                float* row) {
  const bool row_in = j >= pbox.j0 && j < pbox.j0 + pbox.ny;
  const int a = row_in ? std::clamp(pbox.i0, i0, i1) : i1;
  const int b = row_in ? std::clamp(pbox.i0 + pbox.nx, a, i1) : i1;
  std::fill(row + i0, row + a, 0.0f);
  h.p_row(static_cast<size_t>(j) * n + a, b - a, row + a);
  std::fill(row + b, row + i1, 0.0f);
}

// Appends base + i for the i in [i0, i1) with hit(x[i]), in order (a
// counting pass first: hits are rare, and it vectorises).
template <typename Hit>
void AppendHits(const double* x, int i0, int i1, int base, Hit hit, std::vector<int>* out) {
  int hits = 0;
  for (int i = i0; i < i1; ++i) hits += hit(x[i]) ? 1 : 0;
  if (hits == 0) return;
  for (int i = i0; i < i1; ++i)
    if (hit(x[i])) out->push_back(base + i);
}

// The warm start (no terms: cold): *guess = the first term's pressure, or
// with two or more terms max(0, sum of weight x pressure); *solve_box = the
// first term's contact kBoxMarginCells wider (within box); with two or more
// terms, the cells where the guess on *solve_box differs from the weighted
// sum (clipped, or outside the box) in w->u0_fix (ExtrapolatedDisplacement).
// The solve reads the guess on *solve_box only (a periodic operator's:
// everywhere), so only that part is cleared. One pass over the history
// rows: the guess, the contact's extent and the weighted sum (kept in
// w->warm_lin), which is classified once the solve box is known.
void WarmStart(const TaxelGrid& grid, const CellBox& box, const WarmTerm* terms, int nterms,
               bool periodic, std::vector<double>* guess, ElasticStepWork* w, CellBox* solve_box) {
  const int n = grid.n;
  w->u0_fix.clear();
  if (nterms == 0 || periodic || guess->size() != grid.Size()) guess->assign(grid.Size(), 0.0);
  if (nterms == 0) return;
  const bool lin_sum = nterms > 1;
  const CellBox lb = terms[0].block->p_box();
  CellBox both = lb;
  for (int t = 1; t < nterms; ++t) both = Union(both, terms[t].block->p_box());
  const int i0 = both.i0, i1 = both.i0 + both.nx;
  // the rows as stored (float): widened exactly where they are used
  w->row_f.resize(static_cast<size_t>(nterms) * std::max(n, 1));
  float* lrow = w->row_f.data();
  if (lin_sum) w->warm_lin.resize(static_cast<size_t>(std::max(both.nx, 0)) * std::max(both.ny, 0));
  // the first term's contact within box: its cells in box's columns of lb
  const int ia = std::max(box.i0, lb.i0), ib = std::min(box.i0 + box.nx, lb.i0 + lb.nx);
  const int ja = std::max(box.j0, lb.j0), jb = std::min(box.j0 + box.ny, lb.j0 + lb.ny);
  CellBounds support;
  for (int j = both.j0; j < both.j0 + both.ny; ++j) {
    double* g = guess->data() + static_cast<size_t>(j) * n;
    HistoryRow(*terms[0].block, lb, j, n, i0, i1, lrow);
    if (j >= ja && j < jb && ia < ib) {
      int lo = ia, hi = ib - 1;
      while (lo < ib && !(lrow[lo] > 0.0f)) ++lo;
      if (lo < ib) {
        while (!(lrow[hi] > 0.0f)) --hi;
        support.AddRow(lo, hi, j);
      }
    }
    if (!lin_sum) {
      for (int i = i0; i < i1; ++i) g[i] = static_cast<double>(lrow[i]);
      continue;
    }
    for (int t = 1; t < nterms; ++t)
      HistoryRow(*terms[t].block, terms[t].block->p_box(), j, n, i0, i1,
                 lrow + static_cast<size_t>(t) * n);
    double* lin = w->warm_lin.data() + static_cast<size_t>(j - both.j0) * both.nx - i0;
    const double w0 = terms[0].weight;
    for (int i = i0; i < i1; ++i) {
      double v = w0 * static_cast<double>(lrow[i]);
      for (int t = 1; t < nterms; ++t)
        v += terms[t].weight * static_cast<double>(lrow[static_cast<size_t>(t) * n + i]);
      g[i] = std::max(0.0, v);
      lin[i] = v;
    }
  }
  if (!support.empty()) *solve_box = GrowBox(box, support.i0, support.i1, support.j0, support.j1);
  const CellBox sb = *solve_box;
  // the guess zero on sb outside the rows just written
  if (!periodic) {
    for (int j = sb.j0; j < sb.j0 + sb.ny; ++j) {
      double* g = guess->data() + static_cast<size_t>(j) * n;
      const int a = sb.i0, b = sb.i0 + sb.nx;
      if (j < both.j0 || j >= both.j0 + both.ny || i0 >= i1) {
        std::fill(g + a, g + b, 0.0);
      } else {
        std::fill(g + a, g + std::clamp(i0, a, b), 0.0);
        std::fill(g + std::clamp(i1, a, b), g + b, 0.0);
      }
    }
  }
  if (!lin_sum) return;
  for (int j = both.j0; j < both.j0 + both.ny; ++j) {
    const double* lin = w->warm_lin.data() + static_cast<size_t>(j - both.j0) * both.nx - i0;
    // in box order: outside sb, lin != 0; inside, lin < 0
    const bool row_in = j >= sb.j0 && j < sb.j0 + sb.ny;
    const int s0 = row_in ? std::clamp(sb.i0, i0, i1) : i1;
    const int s1 = row_in ? std::clamp(sb.i0 + sb.nx, s0, i1) : i1;
    const int base = j * n;
    auto nonzero = [](double v) { return v != 0.0; };
    AppendHits(lin, i0, s0, base, nonzero, &w->u0_fix);
    AppendHits(lin, s0, s1, base, [](double v) { return v < 0.0; }, &w->u0_fix);
    AppendHits(lin, s1, i1, base, nonzero, &w->u0_fix);
  }
}

// w->u0 = K times the extrapolated guess on `box` (bx * by): by linearity
// the weighted sum of the displacements the terms' steps stored (their box
// checks' K p over kHsURegion*), corrected by direct sums for the cells
// where the guess is not the weighted sum of pressures (clipped at zero, or
// outside the box). False (apply the operator instead) if a stored box does
// not cover `box` or the corrections would cost more than an FFT.
bool ExtrapolatedDisplacement(const TaxelGrid& grid, const SurfaceCompliance& K,
                              const WarmTerm* terms, int nterms, const std::vector<double>& guess,
                              const CellBox& box, int threads, ElasticStepWork* w) {
  auto covers = [&](const CellBox& r) {
    return r.nx > 0 && r.ny > 0 && box.i0 >= r.i0 && box.j0 >= r.j0 &&
           box.i0 + box.nx <= r.i0 + r.nx && box.j0 + box.ny <= r.j0 + r.ny;
  };
  if (K.periodic()) return false;
  for (int t = 0; t < nterms; ++t)
    if (!covers(terms[t].block->u_box())) return false;
  // The cells to correct (WarmStart), and whether they are few enough.
  const size_t B = static_cast<size_t>(box.nx) * box.ny;
  if (static_cast<double>(w->u0_fix.size()) >
      DirectCellsPerApply(*K.SpectrumFor(box.nx, box.ny), B))
    return false;
  w->u0.resize(static_cast<size_t>(box.nx) * box.ny);
  double* u = w->u0.data();
  std::vector<float>& ul = w->row_f;
  ul.resize(static_cast<size_t>(nterms) * box.nx);
  for (int j = 0; j < box.ny; ++j) {
    for (int t = 0; t < nterms; ++t) {
      const CellBox r = terms[t].block->u_box();
      const size_t k = static_cast<size_t>(box.j0 + j - r.j0) * r.nx + (box.i0 - r.i0);
      terms[t].block->u_row(k, box.nx, ul.data() + static_cast<size_t>(t) * box.nx);
    }
    double* urow = u + static_cast<size_t>(j) * box.nx;
    const double w0 = terms[0].weight;
    for (int i = 0; i < box.nx; ++i) {
      double v = w0 * static_cast<double>(ul[i]);
      for (int t = 1; t < nterms; ++t)
        v += terms[t].weight * static_cast<double>(ul[static_cast<size_t>(t) * box.nx + i]);
      urow[i] = v;
    }
  }
  // (in u0_fix's order, several cells per pass over u: AddCellsAt)
  const size_t nfix = w->u0_fix.size();
  w->fix_i.resize(nfix);
  w->fix_j.resize(nfix);
  w->fix_d.resize(nfix);
  for (size_t f = 0; f < nfix; ++f) {
    const int k = w->u0_fix[f];
    const int i = k % grid.n, j = k / grid.n;
    double lin =
        terms[0].weight * HistoryPressure(*terms[0].block, terms[0].block->p_box(), i, j, grid.n);
    for (int t = 1; t < nterms; ++t)
      lin +=
          terms[t].weight * HistoryPressure(*terms[t].block, terms[t].block->p_box(), i, j, grid.n);
    w->fix_i[f] = i - box.i0;
    w->fix_j[f] = j - box.j0;
    w->fix_d[f] = (Inside(box, i, j) ? guess[k] : 0.0) - lin;
  }
  K.AddCellsAt(w->fix_i.data(), w->fix_j.data(), w->fix_d.data(), nfix, box.nx, box.ny, u, threads);
  return true;
}

// Solves the contact on *solve_box from *pressure (u0: K *pressure there, or
// null), checks that no rendered cell of `box` outside it could touch
// (the skin's lift bound lift_m) and grows it around the cells that would,
// after kBoxAttempts on all of `box`. Returns whether the load is carried;
// *solve_box is the final box, *u_region the box over which w->check_u holds
// K p of the solution (nx = 0: none), which the next step's warm start uses.
bool SolveOnGrowingBox(const TaxelGrid& grid, const ElasticContact& ec,
                       const std::vector<double>& gap, const CellBox& box, double force_n,
                       double lift_m, const ElasticSolveOptions& opt, const double* u0,
                       std::vector<double>* pressure, ElasticStepWork* w, ElasticSolveStats* st,
                       CellBox* solve_box, CellBox* u_region) {
  *u_region = CellBox{0, 0, 0, 0};
  bool touching = false;
  for (int attempt = 0;; ++attempt) {
    touching = ec.Solve(gap, *solve_box, force_n, opt, pressure, &w->solve, st,
                        attempt == 0 ? u0 : nullptr);
    const CellBox& sb = *solve_box;
    const bool whole = sb.i0 == box.i0 && sb.j0 == box.j0 && sb.nx == box.nx && sb.ny == box.ny;
    if (whole) break;
    CellBox grown = box;
    if (touching && BoxHoldsContact(grid, ec.compliance(), gap, box, sb, *pressure, st->approach_m,
                                    lift_m, opt, w, &grown, u_region))
      break;
    *u_region = CellBox{0, 0, 0, 0};
    // the solution on the smaller box is a good start on the grown one
    *solve_box = touching && attempt + 1 < kBoxAttempts ? grown : box;
  }
  return touching;
}

}  // namespace

bool HasWarmStart(const HistoryBlock* history) {
  return history && history[1].slots[kHsValid] > 0.0;
}

bool SolveElasticWarm(const TaxelGrid& grid, const ElasticContact& ec, const CellBox& box,
                      const std::vector<double>& coverage, const HistoryBlock* history,
                      double force_n, const ElasticSolveOptions& opt, std::vector<double>* gap,
                      std::vector<double>* pressure, ElasticStepWork* w, ElasticSolveStats* st,
                      CellBox* solve_box, CellBox* u_region) {
  // Warm start: the last step's pressure field (plugin_state), so a sliding
  // contact needs a few iterations. With contact_solver = pcg, extrapolated
  // 2 p(n-1) - p(n-2) when both steps touched (prototype on slide_grating,
  // P&K: 16.6 -> 9.7 iterations at the same error), and its K p from the
  // last two steps' stored K p (linear), which spares the solve an operator
  // application.
  WarmTerm terms[2];
  int nterms = 0;
  if (HasWarmStart(history)) {
    const bool extrapolate =
        opt.method == ElasticMethod::kPreconditioned && history[2].slots[kHsValid] > 0.0;
    terms[nterms++] = WarmTerm{&history[1], extrapolate ? 2.0 : 1.0};
    if (extrapolate) terms[nterms++] = WarmTerm{&history[2], -1.0};
  }
  return SolveElasticWarmFrom(grid, ec, box, coverage, terms, nterms, false, force_n, opt, gap,
                              pressure, w, st, solve_box, u_region);
}

bool SolveElasticWarmFrom(const TaxelGrid& grid, const ElasticContact& ec, const CellBox& box,
                          const std::vector<double>& coverage, const WarmTerm* terms, int nterms,
                          bool single_term_u, double force_n, const ElasticSolveOptions& opt,
                          std::vector<double>* gap, std::vector<double>* pressure,
                          ElasticStepWork* w, ElasticSolveStats* st, CellBox* solve_box,
                          CellBox* u_region) {
  // Cells without coverage never touch (every cell stored, the select
  // vectorises).
  for (int j = box.j0; j < box.j0 + box.ny; ++j) {
    double* g = gap->data() + static_cast<size_t>(j) * grid.n;
    const double* c = coverage.data() + static_cast<size_t>(j) * grid.n;
    for (int i = box.i0; i < box.i0 + box.nx; ++i) g[i] = c[i] > 0.0 ? g[i] : kInf;
  }
  // The solve box: the last step's contact, kBoxMarginCells wider. The gap
  // alone bounds it poorly: an elastic contact is ~1/sqrt(2) as wide as the
  // region where the surfaces interpenetrate, and a layered skin bulges
  // beside a load. So the box is checked after the solve (BoxHoldsContact:
  // no rendered cell outside it may touch) and grown around the cells that
  // would; after kBoxAttempts, every rendered cell. The result solves the
  // contact problem on the rendered cells either way.
  if (nterms > 0)
    WarmStart(grid, box, terms, nterms, ec.compliance().periodic(), pressure, w, solve_box);
  const bool have_u0 = (nterms > 1 || (single_term_u && nterms == 1)) &&
                       ExtrapolatedDisplacement(grid, ec.compliance(), terms, nterms, *pressure,
                                                *solve_box, opt.threads, w);
  // Upward bulge bound: max_lift times the whole load on one cell.
  const double lift = ec.max_lift_m_per_pa() * force_n / grid.Area();
  return SolveOnGrowingBox(grid, ec, *gap, box, force_n, lift, opt,
                           have_u0 ? w->u0.data() : nullptr, pressure, w, st, solve_box, u_region);
}

void StoreElasticHistory(const TaxelGrid& grid, const std::vector<double>& pressure,
                         const CellBox& p_box, const CellBox& u_region,
                         const std::vector<double>& u, double depth_m, HistoryBlock* cur) {
  // Rounded to float in chunks, then copied (stores through the block's
  // char buffer would alias the doubles read).
  float chunk[256];
  auto store = [&](const double* from, size_t count, size_t to) {
    for (size_t done = 0; done < count; done += 256) {
      const size_t m = std::min<size_t>(256, count - done);
      for (size_t k = 0; k < m; ++k) chunk[k] = static_cast<float>(from[done + k]);
      cur->SetRange(to + done, m, chunk);
    }
  };
  for (int j = p_box.j0; j < p_box.j0 + p_box.ny; ++j) {
    const size_t k = static_cast<size_t>(j) * grid.n + p_box.i0;
    store(pressure.data() + k, static_cast<size_t>(std::max(p_box.nx, 0)), k);
  }
  cur->SetSlotBox(kHsPBoxI0, p_box);
  cur->SetSlotBox(kHsURegionI0, u_region);
  store(u.data(), static_cast<size_t>(u_region.nx) * u_region.ny, cur->ncell);
  cur->slots[kHsValid] = 1.0;
  cur->slots[kHsDepth] = depth_m;
}

}  // namespace mjtouch
