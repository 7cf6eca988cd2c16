#include "contact/contact_solver.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mjtouch {

ElasticContact::ElasticContact(std::shared_ptr<const SurfaceCompliance> compliance)
    : compliance_(std::move(compliance)) {}

bool ElasticContact::Solve(const std::vector<double>& gap_m, const CellBox& box,
                           double force_n, double tolerance, int max_iterations,
                           std::vector<double>* pressure_pa, ElasticWork* work,
                           ElasticSolveStats* stats) const {
  return SolveElasticContact(*compliance_, gap_m, box, force_n, tolerance, max_iterations,
                             pressure_pa, work, stats);
}

bool SolveElasticContact(const SurfaceCompliance& K, const std::vector<double>& gap,
                         const CellBox& box_in, double force, double tol, int max_iter,
                         std::vector<double>* pressure, ElasticWork* w, ElasticSolveStats* st) {
  *st = ElasticSolveStats();
  CellBox box = box_in;
  const bool periodic = K.periodic();
  const int nx = K.nx();
  if (periodic) box = {0, 0, nx, K.ny()};
  const int bx = box.nx, by = box.ny;
  const size_t B = static_cast<size_t>(bx) * by;
  const double A = K.pitch_m() * K.pitch_m();
  auto grid_index = [&](size_t b) {
    return static_cast<size_t>(box.j0 + b / bx) * nx + box.i0 + b % bx;
  };
  w->g0.resize(B);
  w->p.resize(B);
  w->u.resize(B);
  w->g.assign(B, 0.0);
  w->t.assign(B, 0.0);
  w->r.resize(B);
  w->p_new.resize(B);
  w->delta.assign(B, 0.0);
  double* g0 = w->g0.data();
  double* p = w->p.data();
  double* u = w->u.data();
  double* g = w->g.data();
  double* t = w->t.data();
  double* r = w->r.data();
  double* pn = w->p_new.data();
  double* dl = w->delta.data();
  size_t ncand = 0;
  double sum_p = 0.0;
  for (size_t b = 0; b < B; ++b) {
    const size_t k = grid_index(b);
    g0[b] = gap[k];
    const bool cand = std::isfinite(g0[b]);
    ncand += cand;
    p[b] = cand ? std::max(0.0, (*pressure)[k]) : 0.0;
    if (!std::isfinite(p[b])) p[b] = 0.0;
    sum_p += p[b];
  }
  std::fill(pressure->begin(), pressure->end(), 0.0);
  const double target = force / A;  // sum of p over cells
  if (ncand == 0 || !(target > 0.0)) return false;
  if (!(sum_p > 0.0)) {
    for (size_t b = 0; b < B; ++b) p[b] = std::isfinite(g0[b]) ? 1.0 : 0.0;
    sum_p = static_cast<double>(ncand);
  }
  for (size_t b = 0; b < B; ++b) p[b] *= target / sum_p;

  const auto spec = K.SpectrumFor(bx, by);
  st->fft_size_x = spec->fft.nx();
  st->fft_size_y = spec->fft.ny();
  const double fft_cost = 5.0 * static_cast<double>(spec->fft.nx()) * spec->fft.ny() *
                          std::log2(static_cast<double>(spec->fft.nx()) * spec->fft.ny());
  K.Apply(*spec, p, bx, by, u, &w->fft);

  double beta_on = 0.0;  // 0: steepest descent step (first, or after new contacts)
  double G_old = 1.0;
  for (int it = 1; it <= max_iter; ++it) {
    st->iterations = it;
    // Gap residual on the contact set, the approach eliminated by its mean.
    size_t nc = 0;
    double sum_g = 0.0;
    for (size_t b = 0; b < B; ++b)
      if (p[b] > 0.0) { sum_g += g0[b] + u[b]; ++nc; }
    const double gbar = sum_g / static_cast<double>(nc);
    double G = 0.0;
    for (size_t b = 0; b < B; ++b) {
      if (!std::isfinite(g0[b])) { g[b] = 0.0; t[b] = 0.0; continue; }
      g[b] = g0[b] + u[b] - gbar;
      if (p[b] > 0.0) G += g[b] * g[b];
    }
    const double beta = beta_on * G / G_old;
    for (size_t b = 0; b < B; ++b) t[b] = p[b] > 0.0 ? g[b] + beta * t[b] : 0.0;
    G_old = G;
    K.Apply(*spec, t, bx, by, r, &w->fft);
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
    if (!(sum_new > 0.0)) break;
    const double s = target / sum_new;
    double change = 0.0;
    for (size_t b = 0; b < B; ++b) {
      const double v = s * pn[b];
      change += std::abs(v - p[b]);
      p[b] = v;
    }
    change /= target;
    st->change = change;
    // u = K p_new = s (u - tau K t + K delta): delta is the projection's
    // correction; few cells change near convergence, so sum it directly
    // unless an FFT is cheaper.
    for (size_t b = 0; b < B; ++b) u[b] -= tau * r[b];
    const size_t nchg = w->changed.size();
    if (nchg > 0) {
      if (static_cast<double>(nchg) * static_cast<double>(B) < fft_cost || periodic) {
        if (periodic) {
          K.Apply(*spec, dl, bx, by, r, &w->fft);
          for (size_t b = 0; b < B; ++b) u[b] += r[b];
        } else {
          for (int c : w->changed) K.AddCell(c, dl[c], bx, by, u);
        }
      } else {
        K.Apply(*spec, dl, bx, by, r, &w->fft);
        for (size_t b = 0; b < B; ++b) u[b] += r[b];
      }
      for (int c : w->changed) dl[c] = 0.0;
    }
    for (size_t b = 0; b < B; ++b) u[b] *= s;
    if (change < tol) {
      st->converged = true;
      break;
    }
  }
  // Exact displacement of the final pressure for the approach and the check.
  K.Apply(*spec, p, bx, by, u, &w->fft);
  size_t nc = 0;
  double sum_g = 0.0, max_g = -std::numeric_limits<double>::infinity();
  for (size_t b = 0; b < B; ++b) {
    if (p[b] > 0.0) {
      sum_g += g0[b] + u[b];
      max_g = std::max(max_g, g0[b]);
      ++nc;
    }
  }
  st->contact_cells = static_cast<int>(nc);
  st->approach_m = nc ? sum_g / static_cast<double>(nc) : 0.0;
  st->max_contact_gap_m = max_g;
  for (size_t b = 0; b < B; ++b) (*pressure)[grid_index(b)] = p[b];
  return nc > 0;
}

}  // namespace mjtouch
