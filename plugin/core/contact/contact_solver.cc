#include "contact/contact_solver.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mjtouch {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Antiderivative of 1/r: d^2 Phi / dX dY = 1 / sqrt(X^2 + Y^2).
double Phi(double X, double Y) {
  double out = 0.0;
  if (X != 0.0) out += X * std::asinh(Y / std::abs(X));
  if (Y != 0.0) out += Y * std::asinh(X / std::abs(Y));
  return out;
}

}  // namespace

void HalfSpaceSurfaceComplianceTable(double young_pa, double poisson, double h, int n,
                                     std::vector<float>* table) {
  const int L = 2 * n - 1;
  table->assign(static_cast<size_t>(L) * L, 0.0f);
  const double e_star = young_pa / (1.0 - poisson * poisson);
  const double scale = 1.0 / (kPi * e_star);
  const double a = 0.5 * h;
  for (int dj = 0; dj < n; ++dj) {
    for (int di = 0; di < n; ++di) {
      // Field point at (x, y) = offset of the receptor cell from the loaded
      // one: minus (di, dj) h; the response is even in both.
      const double x = di * h, y = dj * h;
      const double v = scale * (Phi(x + a, y + a) - Phi(x + a, y - a) - Phi(x - a, y + a) +
                                Phi(x - a, y - a));
      const float f = static_cast<float>(v);
      for (int sj : {-1, 1})
        for (int si : {-1, 1})
          (*table)[static_cast<size_t>(sj * dj + n - 1) * L + (si * di + n - 1)] = f;
    }
  }
}

ElasticContact::ElasticContact(int n, double pitch_m, std::vector<float> table)
    : periodic_(false), nx_(n), ny_(n), n_(n), pitch_m_(pitch_m), table_(std::move(table)) {
  for (float v : table_) max_lift_ = std::max(max_lift_, -static_cast<double>(v));
}

ElasticContact::ElasticContact(int nx, int ny, double pitch_m,
                               const std::function<double(double)>& c_of_k)
    : periodic_(true), nx_(nx), ny_(ny), n_(0), pitch_m_(pitch_m) {
  auto s = std::make_shared<Spectrum>(nx, ny);
  s->k_hat.assign(s->fft.spectrum_size(), 0.0);
  const int ls = s->fft.spectrum_stride();
  const double norm = 1.0 / (static_cast<double>(nx) * ny);
  for (int kx = 0; kx < nx; ++kx) {
    const int fx = kx <= nx / 2 ? kx : kx - nx;
    for (int ky = 0; ky < ny; ++ky) {
      const int fy = ky <= ny / 2 ? ky : ky - ny;
      if (fx == 0 && fy == 0) continue;
      const double k = 2.0 * kPi * std::hypot(fx / (nx * pitch_m), fy / (ny * pitch_m));
      s->k_hat[static_cast<size_t>(kx) * ls + ky] = c_of_k(k) * norm;
    }
  }
  periodic_spectrum_ = std::move(s);
}

std::shared_ptr<const ElasticContact::Spectrum> ElasticContact::SpectrumFor(int bx,
                                                                             int by) const {
  if (periodic_) return periodic_spectrum_;
  const int mx = NextFftSize(2 * bx - 1), my = NextFftSize(2 * by - 1);
  std::lock_guard<std::mutex> lock(mu_);
  auto& slot = spectra_[{mx, my}];
  if (slot) return slot;
  // The kernel wrapped onto the mx x my torus: offsets up to the box size
  // matter; it is even in both axes, so its transform is real.
  auto s = std::make_shared<Spectrum>(mx, my);
  std::vector<double> kr(static_cast<size_t>(mx) * my, 0.0);
  for (int y = 0; y < my; ++y) {
    const int dy = y <= my / 2 ? y : y - my;
    if (std::abs(dy) > n_ - 1) continue;
    for (int x = 0; x < mx; ++x) {
      const int dx = x <= mx / 2 ? x : x - mx;
      if (std::abs(dx) > n_ - 1) continue;
      kr[static_cast<size_t>(y) * mx + x] = TableAt(dx, dy);
    }
  }
  std::vector<double> sre(s->fft.spectrum_size()), sim(s->fft.spectrum_size()), scratch;
  s->fft.Forward(kr.data(), nullptr, mx, my, mx, sre.data(), sim.data(), &scratch);
  const double norm = 1.0 / (static_cast<double>(mx) * my);
  s->k_hat.resize(sre.size());
  for (size_t k = 0; k < sre.size(); ++k) s->k_hat[k] = sre[k] * norm;
  slot = std::move(s);
  return slot;
}

void ElasticContact::Convolve(const Spectrum& s, const double* in, int bx, int by,
                              double* out, ElasticWork* w) const {
  // Real field, real even kernel: half spectra (Fft2D::ForwardReal).
  const size_t S = s.fft.spectrum_size();
  w->spec_re.resize(S);
  w->spec_im.resize(S);
  s.fft.ForwardReal(in, bx, by, bx, w->spec_re.data(), w->spec_im.data(), &w->fft_scratch);
  const double* k = s.k_hat.data();
  double* re = w->spec_re.data();
  double* im = w->spec_im.data();
  const int ls = s.fft.spectrum_stride(), hy = s.fft.half_ny();
  for (int kx = 0; kx < s.fft.nx(); ++kx)
    for (int ky = 0; ky < hy; ++ky) {
      const size_t i = static_cast<size_t>(kx) * ls + ky;
      re[i] *= k[i];
      im[i] *= k[i];
    }
  s.fft.InverseReal(re, im, by, bx, out, bx, &w->fft_scratch);
}

void ElasticContact::Displacement(const std::vector<double>& pressure, const CellBox& box,
                                  std::vector<double>* u, ElasticWork* w) const {
  const int bx = periodic_ ? nx_ : box.nx, by = periodic_ ? ny_ : box.ny;
  const int i0 = periodic_ ? 0 : box.i0, j0 = periodic_ ? 0 : box.j0;
  std::vector<double> p(static_cast<size_t>(bx) * by);
  for (int j = 0; j < by; ++j)
    for (int i = 0; i < bx; ++i)
      p[static_cast<size_t>(j) * bx + i] = pressure[static_cast<size_t>(j0 + j) * nx_ + i0 + i];
  u->assign(p.size(), 0.0);
  Convolve(*SpectrumFor(bx, by), p.data(), bx, by, u->data(), w);
}

bool ElasticContact::Solve(const std::vector<double>& gap, const CellBox& box_in, double force,
                           double tol, int max_iter, std::vector<double>* pressure,
                           ElasticWork* w, ElasticSolveStats* st) const {
  *st = ElasticSolveStats();
  CellBox box = box_in;
  if (periodic_) box = {0, 0, nx_, ny_};
  const int bx = box.nx, by = box.ny;
  const size_t B = static_cast<size_t>(bx) * by;
  const double A = pitch_m_ * pitch_m_;
  auto grid_index = [&](size_t b) {
    return static_cast<size_t>(box.j0 + b / bx) * nx_ + box.i0 + b % bx;
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

  const auto spec = SpectrumFor(bx, by);
  st->fft_size_x = spec->fft.nx();
  st->fft_size_y = spec->fft.ny();
  const double fft_cost = 5.0 * static_cast<double>(spec->fft.nx()) * spec->fft.ny() *
                          std::log2(static_cast<double>(spec->fft.nx()) * spec->fft.ny());
  Convolve(*spec, p, bx, by, u, w);

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
    Convolve(*spec, t, bx, by, r, w);
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
      if (static_cast<double>(nchg) * static_cast<double>(B) < fft_cost || periodic_) {
        if (periodic_) {
          Convolve(*spec, dl, bx, by, r, w);
          for (size_t b = 0; b < B; ++b) u[b] += r[b];
        } else {
          for (int c : w->changed) {
            const int ci = c % bx, cj = c / bx;
            const double d = dl[c];
            for (int j = 0; j < by; ++j) {
              double* urow = u + static_cast<size_t>(j) * bx;
              const float* krow = table_.data() +
                                  static_cast<size_t>(cj - j + n_ - 1) * (2 * n_ - 1) +
                                  (ci + n_ - 1);
              // K(ci - i, cj - j): walk the table row backwards with i.
              for (int i = 0; i < bx; ++i) urow[i] += d * krow[-i];
            }
          }
        }
      } else {
        Convolve(*spec, dl, bx, by, r, w);
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
  Convolve(*spec, p, bx, by, u, w);
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
