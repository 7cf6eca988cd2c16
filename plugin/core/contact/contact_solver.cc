#include "contact/contact_solver.h"

#include <algorithm>
#include <cmath>

#include "common/simd.h"
#include "common/thread_pool.h"
#include "contact/working_set.h"

namespace mjtouch {
namespace {

// One solve's box, arrays and operator, shared by the two iterations.
struct Problem {
  const SurfaceCompliance& K;
  std::shared_ptr<const SurfaceCompliance::Spectrum> spec;
  int bx, by;
  size_t B;
  bool periodic;
  double target;    // sum of p over cells (force / cell area)
  double fft_cost;  // flops of one Apply, against direct sums
  ElasticWork* w;
  ApplyPrecision precision;
  int threads;  // ThreadPool callers of the FFTs and the stencil
};

// sum of term(k), k < n, in four interleaved partial sums combined as
// (s0 + s1) + (s2 + s3): one fixed order on every instruction set (so
// deterministic), without one running sum's add-latency chain. term is
// called once per k, in increasing k (it may write per-k outputs).
template <typename F>
inline double Sum4(size_t n, F term) {
  double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
  size_t k = 0;
  for (; k + 4 <= n; k += 4) {
    s0 += term(k);
    s1 += term(k + 1);
    s2 += term(k + 2);
    s3 += term(k + 3);
  }
  for (; k < n; ++k) s0 += term(k);
  return (s0 + s1) + (s2 + s3);
}

// u = s (u - tau r + K delta) after a step p - tau t whose projection onto
// p >= 0 added delta on the cells in w->changed: few cells change near
// convergence, so sum them directly unless an FFT is cheaper.
void UpdateDisplacement(const Problem& P, double tau, double s, ElasticSolveStats* st) {
  ElasticWork* w = P.w;
  double* u = w->u.data();
  double* r = w->r.data();
  double* dl = w->delta.data();
  for (size_t b = 0; b < P.B; ++b) u[b] -= tau * r[b];
  const size_t nchg = w->changed.size();
  if (nchg > 0) {
    if (!P.periodic && static_cast<double>(nchg) * static_cast<double>(P.B) < P.fft_cost) {
      P.K.AddCells(w->changed.data(), nchg, dl, P.bx, P.by, u, P.threads);
    } else {
      P.K.Apply(*P.spec, dl, P.bx, P.by, r, &w->fft, P.precision, P.threads);
      ++st->applies;
      for (size_t b = 0; b < P.B; ++b) u[b] += r[b];
    }
    for (int c : w->changed) dl[c] = 0.0;
  }
  for (size_t b = 0; b < P.B; ++b) u[b] *= s;
}

// Rescale p_new to the load; the relative L1 change (the stopping test).
double Accept(const Problem& P, double sum_new, double* s_out) {
  double* p = P.w->p.data();
  const double* pn = P.w->p_new.data();
  const double s = P.target / sum_new;
  const double change = Sum4(P.B, [&](size_t b) {
    const double v = s * pn[b], d = std::abs(v - p[b]);
    p[b] = v;
    return d;
  });
  *s_out = s;
  return change / P.target;
}

void PolonskyKeer(const Problem& P, double tol, int max_iter, ElasticSolveStats* st) {
  ElasticWork* w = P.w;
  const size_t B = P.B;
  double* g0 = w->g0.data();
  double* p = w->p.data();
  double* u = w->u.data();
  double* g = w->g.data();
  double* t = w->t.data();
  double* r = w->r.data();
  double* pn = w->p_new.data();
  double* dl = w->delta.data();
  double beta_on = 0.0;  // 0: steepest descent step (first, or after new contacts)
  double G_old = 1.0;
  for (int it = 1; it <= max_iter; ++it) {
    st->iterations = it;
    // Gap residual on the contact set, the approach eliminated by its mean.
    size_t nc = 0;
    double sum_g = 0.0;
    for (size_t b = 0; b < B; ++b)
      if (p[b] > 0.0) {
        sum_g += g0[b] + u[b];
        ++nc;
      }
    const double gbar = sum_g / static_cast<double>(nc);
    double G = 0.0;
    for (size_t b = 0; b < B; ++b) {
      if (!std::isfinite(g0[b])) {
        g[b] = 0.0;
        t[b] = 0.0;
        continue;
      }
      g[b] = g0[b] + u[b] - gbar;
      if (p[b] > 0.0) G += g[b] * g[b];
    }
    const double beta = beta_on * G / G_old;
    for (size_t b = 0; b < B; ++b) t[b] = p[b] > 0.0 ? g[b] + beta * t[b] : 0.0;
    G_old = G;
    P.K.Apply(*P.spec, t, P.bx, P.by, r, &w->fft, P.precision, P.threads);
    ++st->applies;
    double sum_r = 0.0;
    for (size_t b = 0; b < B; ++b)
      if (p[b] > 0.0) sum_r += r[b];
    const double rbar = sum_r / static_cast<double>(nc);
    double num = 0.0, den = 0.0;
    for (size_t b = 0; b < B; ++b) {
      if (p[b] > 0.0) {
        num += g[b] * t[b];
        den += (r[b] - rbar) * t[b];
      }
    }
    if (!(den > 0.0) || !(G > 0.0)) {  // exact solution (or degenerate)
      st->converged = G == 0.0;
      break;
    }
    const double tau = num / den;
    // Step, project onto p >= 0, and admit overlapping cells (P&K's I_ol).
    w->changed.clear();
    bool overlap = false;
    double sum_new = 0.0;
    for (size_t b = 0; b < B; ++b) {
      double v = 0.0;
      if (p[b] > 0.0) {
        v = p[b] - tau * t[b];
        if (v < 0.0) {
          dl[b] = -v;
          w->changed.push_back(static_cast<int>(b));
          v = 0.0;
        }
      } else if (std::isfinite(g0[b]) && g[b] < 0.0) {
        v = -tau * g[b];
        dl[b] = v;
        w->changed.push_back(static_cast<int>(b));
        overlap = true;
      }
      pn[b] = v;
      sum_new += v;
    }
    beta_on = overlap ? 0.0 : 1.0;
    if (!(sum_new > 0.0)) {
      for (int c : w->changed) dl[c] = 0.0;  // delta stays zero
      break;
    }
    double s;
    st->change = Accept(P, sum_new, &s);
    UpdateDisplacement(P, tau, s, st);
    if (st->change < tol) {
      st->converged = true;
      break;
    }
  }
}

// z[j * bx + i] = sum over (dj, di) in stencil order of M[dj L + di] *
// g_pad[(j + dj) px + i + di], for i in [lo[j], hi[j]) (the solver reads z
// on its working set only; elsewhere z is left as it was). The stencil
// unrolled inside the loop over i, which vectorises: each cell's sum runs
// in the same order as a per-cell loop would, in a register.
// T: the arithmetic (float with ApplyPrecision::kFloat: twice the lanes; the
// preconditioner only shapes the search direction, so its rounding moves
// the iterates, not the converged solution).
template <int L, typename T>
MJTOUCH_TARGET_CLONES void ApplyStencil(const double* M, const T* g_pad, int px, int bx, int by,
                                        const int* lo, const int* hi, double* z_out) {
  T m[L * L];
  for (int k = 0; k < L * L; ++k) m[k] = static_cast<T>(M[k]);
  for (int j = 0; j < by; ++j) {
    double* __restrict z = z_out + static_cast<size_t>(j) * bx;
    const T* __restrict row = g_pad + static_cast<size_t>(j) * px;
    for (int i = lo[j]; i < hi[j]; ++i) {
      T acc = 0;
#pragma GCC unroll 32
      for (int dj = 0; dj < L; ++dj)
#pragma GCC unroll 8
        for (int di = 0; di < L; ++di)
          acc += m[dj * L + di] * row[static_cast<size_t>(dj) * px + i + di];
      z[i] = static_cast<double>(acc);
    }
  }
}

// ApplyStencil with the rows split over `threads` pool callers (each row's
// sums are its own: the same bits for any split).
template <int L, typename T>
void StencilRows(const double* M, const T* g_pad, int px, int bx, int by, const int* lo,
                 const int* hi, double* z_out, int threads) {
  ForRowParts(by, threads, 8, [&](int j0, int j1) {
    ApplyStencil<L>(M, g_pad + static_cast<size_t>(j0) * px, px, bx, j1 - j0, lo + j0, hi + j0,
                    z_out + static_cast<size_t>(j0) * bx);
  });
}

// The working set's values live in contiguous arrays (working_set.h), whose
// four-lane passes sum in Sum4's order; the box keeps t (zero off the set,
// the operator's input), p, u and the operator outputs.
// gap_sum, contacts: the first iteration's contact gap sum and size if
// known (ScaleStart), else contacts = 0.
void Preconditioned(const Problem& P, double tol, int max_iter, double gap_sum, size_t contacts,
                    ElasticSolveStats* st) {
  namespace ws = working_set;
  ElasticWork* w = P.w;
  const size_t B = P.B;
  const int bx = P.bx, by = P.by;
  constexpr int hw = SurfaceCompliance::kInverseHalfWidth, L = 2 * hw + 1;
  const int px = bx + 2 * hw;  // padded row length
  const double* M = P.spec->inverse.data();
  double* g0 = w->g0.data();
  double* p = w->p.data();
  double* u = w->u.data();
  double* g = w->g.data();  // scratch: K delta
  double* t = w->t.data();  // zero off the last iteration's set (BuildSet zeroes it)
  double* r = w->r.data();
  double* dl = w->delta.data();
  const bool stencil_f = P.precision == ApplyPrecision::kFloat;
  const size_t pad_size = static_cast<size_t>(px) * (by + 2 * hw);
  if (stencil_f) {
    w->g_pad_f.resize(pad_size);  // BuildSet writes every element
  } else {
    w->g_pad.resize(pad_size);
  }
  double* gp = w->g_pad.data();
  float* gpf = w->g_pad_f.data();
  for (auto* v : {&w->set_g, &w->set_z, &w->set_t, &w->set_t_old, &w->set_p, &w->set_p_new})
    v->resize(B);
  w->set.resize(B);
  w->set_rows.resize(static_cast<size_t>(by) + 1);
  w->set_lo.resize(by);
  w->set_hi.resize(by);
  // (kept at B entries: no clearing per solve)
  w->set_changed.resize(std::max(w->set_changed.size(), B));
  double* gS = w->set_g.data();
  double* zS = w->set_z.data();
  double* tS = w->set_t.data();
  double* oS = w->set_t_old.data();
  double* pS = w->set_p.data();
  double* pnS = w->set_p_new.data();
  double G_old = 1.0;
  bool first = true;
  // The contact's gap sum and size for the next iteration (the first from
  // the initial u; later ones from the displacement update's pass).
  size_t nc = contacts;
  double sum_g = nc > 0 ? gap_sum : ws::ContactGapSum(B, g0, u, p, &nc);
  size_t ns = 0;  // |S|
  for (int it = 1; it <= max_iter; ++it) {
    st->iterations = it;
    const double gbar = sum_g / static_cast<double>(nc);
    // The working set S: the contact plus cells that overlap; t lives on it.
    // g_pad: g on S, zero elsewhere (its border zero, or wrapped below);
    // the last t gathered on S (zero before the first), then zeroed.
    const int* S = w->set.data();
    ns = ws::BuildSet(bx, by, px, hw, g0, u, p, gbar, stencil_f ? nullptr : gp, gpf, t, !first,
                      w->set.data(), gS, pS, oS, w->set_rows.data());
    // each row's span of S (empty rows: lo = hi = 0), where z is needed
    for (int j = 0; j < by; ++j) {
      const size_t k0 = w->set_rows[j], k1 = w->set_rows[j + 1];
      const bool any = k1 > k0;
      w->set_lo[j] = any ? S[k0] - j * bx : 0;
      w->set_hi[j] = any ? S[k1 - 1] - j * bx + 1 : 0;
    }
    // A periodic operator's stencil wraps: the border repeats the far side
    // (so a field uniform along an axis stays exactly uniform).
    if (P.periodic) {
      for (int jj = 0; jj < by + 2 * hw; ++jj) {
        const int j = ((jj - hw) % by + by) % by;
        const bool border_row = jj < hw || jj >= by + hw;
        for (int ii = 0; ii < px; ++ii) {
          if (!border_row && ii >= hw && ii < bx + hw) continue;
          const int i = ((ii - hw) % bx + bx) % bx;
          const size_t to = static_cast<size_t>(jj) * px + ii;
          const size_t from = static_cast<size_t>(j + hw) * px + i + hw;
          if (stencil_f) {
            gpf[to] = gpf[from];
          } else {
            gp[to] = gp[from];
          }
        }
      }
    }
    // z = M g on S (M: the inverse operator's stencil, g zero off S), then
    // its mean removed: a direction that keeps the load.
    // Over each row's span of S (vectorises; each cell's sum runs in the
    // stencil's order, as a per-cell loop would), read on S only.
    // r: scratch until K t below.
    const int* lo = w->set_lo.data();
    const int* hi = w->set_hi.data();
    if (stencil_f) {
      StencilRows<L>(M, gpf, px, bx, by, lo, hi, r, P.threads);
    } else {
      StencilRows<L>(M, gp, px, bx, by, lo, hi, r, P.threads);
    }
    const double zbar = ws::GatherSum(ns, S, r, zS) / static_cast<double>(ns);
    const double G = ws::CenterDot(ns, zbar, zS, gS);
    if (!(G > 0.0)) {  // exact solution (or a set the stencil cannot move)
      st->converged = G == 0.0;
      break;
    }
    // t = z + beta t on S, zero off it, projected onto zero net load (cells
    // that left S take their share of the old t with them). No restart when
    // cells join the set: on the sliding scenes that took 6.4 -> 5.4 mean
    // iterations at a lower largest error; a direction that is no longer
    // a descent direction falls back to z.
    double beta = first ? 0.0 : G / G_old;
    first = false;
    G_old = G;
    // (each pass also writes t on the box: zero off S since BuildSet)
    double num = 0.0;
    for (int pass = 0; pass < 2; ++pass) {
      const double tbar = ws::AxpySum(ns, beta, zS, oS, tS) / static_cast<double>(ns);
      num = ws::CenterDot(ns, tbar, tS, gS, S, t);
      if (num > 0.0 || beta == 0.0) break;
      beta = 0.0;
    }
    P.K.Apply(*P.spec, t, bx, by, r, &w->fft, P.precision, P.threads);
    ++st->applies;
    // t sums to zero over S: t.(K t - mean) = t.K t
    const double den = ws::GatherDot(ns, S, r, tS);
    if (!(den > 0.0) || !(num > 0.0)) {
      st->converged = false;
      break;
    }
    const double tau = num / den;
    // Step and project onto p >= 0 on S; off S, p and p_new are zero (p > 0
    // lies in S), so the rescaling and the stopping test run on S only.
    size_t nchg = 0;
    const double sum_new =
        ws::StepProject(ns, tau, pS, tS, S, pnS, dl, w->set_changed.data(), &nchg);
    if (!(sum_new > 0.0)) {
      for (size_t k = 0; k < nchg; ++k) dl[w->set_changed[k]] = 0.0;  // delta stays zero
      break;
    }
    const double s = P.target / sum_new;
    st->change = ws::ScaleChange(ns, s, pnS, pS, S, p) / P.target;
    // u = s (u - tau K t + K delta), K delta by direct sums (few cells) or
    // into g (free until the next iteration), in one pass that also sums
    // the next iteration's contact gap.
    const int* chg = w->set_changed.data();
    double* kd = nullptr;
    if (nchg > 0) {
      if (!P.periodic && static_cast<double>(nchg) < DirectCellsPerApply(*P.spec, B)) {
        P.K.AddCells(chg, nchg, dl, bx, by, u, P.threads);
      } else {
        P.K.Apply(*P.spec, dl, bx, by, g, &w->fft, P.precision, P.threads);
        ++st->applies;
        kd = g;
      }
      for (size_t k = 0; k < nchg; ++k) dl[chg[k]] = 0.0;
    }
    sum_g = ws::UpdateAndSum(B, s, tau, r, kd, g0, p, u, &nc);
    if (st->change < tol) {
      st->converged = true;
      break;
    }
  }
}

}  // namespace

ElasticContact::ElasticContact(std::shared_ptr<const SurfaceCompliance> compliance)
    : compliance_(std::move(compliance)) {}

bool ElasticContact::Solve(const std::vector<double>& gap_m, const CellBox& box, double force_n,
                           const ElasticSolveOptions& options, std::vector<double>* pressure_pa,
                           ElasticWork* work, ElasticSolveStats* stats,
                           const double* initial_u_m) const {
  return SolveElasticContact(*compliance_, gap_m, box, force_n, options, pressure_pa, work, stats,
                             initial_u_m);
}

bool SolveElasticContact(const SurfaceCompliance& K, const std::vector<double>& gap,
                         const CellBox& box_in, double force, const ElasticSolveOptions& opt,
                         std::vector<double>* pressure, ElasticWork* w, ElasticSolveStats* st,
                         const double* initial_u) {
  *st = ElasticSolveStats();
  CellBox box = box_in;
  const bool periodic = K.periodic();
  const int nx = K.nx();
  if (periodic) box = {0, 0, nx, K.ny()};
  const int bx = box.nx, by = box.ny;
  const size_t B = static_cast<size_t>(bx) * by;
  const double A = K.pitch_m() * K.pitch_m();
  // The box's row j starts at grid cell row_start(j).
  auto row_start = [&](int j) { return static_cast<size_t>(box.j0 + j) * nx + box.i0; };
  w->g0.resize(B);
  w->p.resize(B);
  w->u.resize(B);
  // delta is zero between solves (both methods clear the cells they set)
  w->delta.resize(B);
  if (opt.method == ElasticMethod::kPreconditioned) {
    // written before they are read (t: zeroed by BuildSet, g: K delta, r:
    // the stencil's output)
    w->t.resize(B);
    w->g.resize(B);
    w->r.resize(B);
  } else {
    w->t.assign(B, 0.0);
    w->g.assign(B, 0.0);
    w->r.assign(B, 0.0);
    w->p_new.assign(B, 0.0);
  }
  double* g0 = w->g0.data();
  double* p = w->p.data();
  size_t ncand = 0;
  // Cells of the guess the solve drops (their share of initial_u removed;
  // the buffer kept at B entries: no clearing per solve).
  w->dropped.resize(std::max(w->dropped.size(), B));
  const int* dropped = w->dropped.data();
  size_t ndropped = 0;
  double sum_p =
      working_set::LoadGuess(bx, by, nx, gap.data() + row_start(0), pressure->data() + row_start(0),
                             g0, p, &ncand, w->dropped.data(), &ndropped);
  // initial_u, corrected for the dropped cells (direct sums unless they
  // are many), or a fresh K p.
  bool have_u = initial_u != nullptr && !periodic && opt.method == ElasticMethod::kPreconditioned &&
                sum_p > 0.0;
  if (have_u) {
    // Too many dropped cells: the FFT is cheaper.
    have_u = static_cast<double>(ndropped) <= DirectCellsPerApply(*K.SpectrumFor(bx, by), B);
    if (have_u && ndropped > 0) {
      std::copy(initial_u, initial_u + B, w->u.begin());
      for (size_t k = 0; k < ndropped; ++k) {
        const int c = dropped[k];
        const double given = (*pressure)[row_start(c / bx) + c % bx];
        if (std::isfinite(given))
          K.AddCell(c, p[c] - given, bx, by, w->u.data());
        else
          have_u = false;
      }
    }
  }
  // The pressure outside the box is zero; inside it the solution (below).
  const bool scaled_copy = have_u && ndropped == 0;  // u = scale initial_u
  w->changed.clear();
  double* out = pressure->data();
  // (between two box rows one run: the end of one grid row and the start
  // of the next)
  if (by > 0) {
    std::fill(out, out + row_start(0), 0.0);
    for (int j = 0; j + 1 < by; ++j)
      std::fill(out + row_start(j) + bx, out + row_start(j + 1), 0.0);
    std::fill(out + row_start(by - 1) + bx, out + pressure->size(), 0.0);
  } else {
    std::fill(out, out + pressure->size(), 0.0);
  }
  const double target = force / A;  // sum of p over cells
  if (ncand == 0 || !(target > 0.0)) {
    for (int j = 0; j < by; ++j) std::fill(out + row_start(j), out + row_start(j) + bx, 0.0);
    return false;
  }
  if (!(sum_p > 0.0)) {
    for (size_t b = 0; b < B; ++b) p[b] = std::isfinite(g0[b]) ? 1.0 : 0.0;
    sum_p = static_cast<double>(ncand);
  }
  const double scale = target / sum_p;
  // pcg from initial_u: p and u scaled in the pass that sums the first
  // iteration's contact gap
  size_t contacts = 0;
  double gap_sum = 0.0;
  if (have_u) {
    gap_sum = working_set::ScaleStart(B, scale, p, scaled_copy ? initial_u : w->u.data(),
                                      w->u.data(), g0, &contacts);
  } else {
    for (size_t b = 0; b < B; ++b) p[b] *= scale;
  }

  const auto spec = K.SpectrumFor(bx, by);
  st->fft_size_x = spec->fft.nx();
  st->fft_size_y = spec->fft.ny();
  const double fft_cost = 5.0 * static_cast<double>(spec->fft.nx()) * spec->fft.ny() *
                          std::log2(static_cast<double>(spec->fft.nx()) * spec->fft.ny());
  if (!have_u) {
    K.Apply(*spec, p, bx, by, w->u.data(), &w->fft, opt.precision, opt.threads);
    st->applies = 1;
  }
  const Problem P{K, spec, bx, by, B, periodic, target, fft_cost, w, opt.precision, opt.threads};
  if (opt.method == ElasticMethod::kPolonskyKeer) {
    PolonskyKeer(P, opt.tolerance, opt.max_iterations, st);
  } else {
    Preconditioned(P, opt.tolerance, opt.max_iterations, gap_sum, contacts, st);
  }
  // The displacement of the final pressure for the approach: P&K recomputes
  // it; the preconditioned path keeps the running u = K p (updated with the
  // same kernel, by FFT or direct sums: rounding-level differences, 1e-13
  // relative, not worth an FFT pair per step).
  p = w->p.data();
  double* u = w->u.data();
  if (opt.method == ElasticMethod::kPolonskyKeer) {
    K.Apply(*spec, p, bx, by, u, &w->fft, opt.precision, opt.threads);
    ++st->applies;
  }
  size_t nc = 0;
  double max_g = 0.0;
  const double sum_g = working_set::ContactSummary(B, g0, u, p, &nc, &max_g);
  st->contact_cells = static_cast<int>(nc);
  st->approach_m = nc ? sum_g / static_cast<double>(nc) : 0.0;
  st->max_contact_gap_m = max_g;
  for (int j = 0; j < by; ++j)
    std::copy(p + static_cast<size_t>(j) * bx, p + static_cast<size_t>(j + 1) * bx,
              pressure->begin() + row_start(j));
  return nc > 0;
}

}  // namespace mjtouch
