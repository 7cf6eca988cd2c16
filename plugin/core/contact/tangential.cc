#include "contact/tangential.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace mjtouch {
namespace {

constexpr double kPi = 3.14159265358979323846;
// |F| from this share of mu P up counts as full slip: the stick zone left
// (c/a = (1 - |F|/(mu P))^(1/3) < 1e-4) is below any grid, and |F| = mu P
// given by the caller must not miss the branch by round-off.
constexpr double kFullSlipShare = 1.0 - 1e-12;
// Inexact Newton (elastic): each step's CG stops at this share of the last
// step's relative change of q (the sets far from settled need no tight
// solve), at the tolerance at the latest.
constexpr double kNewtonForcing = 0.1;

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", v);
  return buf;
}

// Primitives of the Cerruti kernels over a rectangle (their mixed second
// derivatives): d2/dxdy of x asinh(y/|x|) is y^2/r^3 (+ terms in x alone,
// which a corner sum cancels), of y asinh(x/|y|) is x^2/r^3, of -r is x y / r^3.
double PrimA(double x, double y) { return x == 0.0 ? 0.0 : x * std::asinh(y / std::fabs(x)); }
double PrimB(double x, double y) { return y == 0.0 ? 0.0 : y * std::asinh(x / std::fabs(y)); }
double PrimR(double x, double y) { return -std::hypot(x, y); }

template <typename F>
double CornerSum(F f, double x, double y, double h) {
  const double a = 0.5 * h;
  return f(x + a, y + a) - f(x - a, y + a) - f(x + a, y - a) + f(x - a, y - a);
}

// The loaded cells (p > 0) of a step, in index order, with their disk radii.
struct Cells {
  std::vector<int> index;   // grid index
  std::vector<double> g;    // mu p, Pa
  double pressure_sum = 0;  // sum of p, Pa (force / cell area)
  double g_sum = 0;
};

// The box to scan: the given pressure box, else the whole grid.
CellBox ScanBox(const TaxelGrid& grid, const CellBox* box) {
  return box ? *box : CellBox::All(grid);
}

Cells LoadedCells(const TaxelGrid& grid, const std::vector<double>& pressure_pa, double mu,
                  const CellBox& box) {
  Cells c;
  for (int j = box.j0; j < box.j0 + box.ny; ++j)
    for (int i = box.i0; i < box.i0 + box.nx; ++i) {
      const size_t k = static_cast<size_t>(j) * grid.n + i;
      if (pressure_pa[k] > 0.0) {
        c.index.push_back(static_cast<int>(k));
        c.g.push_back(mu * pressure_pa[k]);
        c.pressure_sum += pressure_pa[k];
        c.g_sum += mu * pressure_pa[k];
      }
    }
  return c;
}

// The state's tractions zeroed (sized to the grid), over their support
// when known.
void ClearTractions(const TaxelGrid& grid, TangentialState* state) {
  const size_t N = grid.Size();
  if (state->shear_x_pa.size() != N || state->shear_y_pa.size() != N || !state->support_known) {
    state->shear_x_pa.assign(N, 0.0);
    state->shear_y_pa.assign(N, 0.0);
  } else {
    const CellBox& b = state->support;
    for (int j = b.j0; j < b.j0 + b.ny; ++j) {
      const size_t k = static_cast<size_t>(j) * grid.n + b.i0;
      std::fill_n(state->shear_x_pa.begin() + k, b.nx, 0.0);
      std::fill_n(state->shear_y_pa.begin() + k, b.nx, 0.0);
    }
  }
  state->support = CellBox{};
  state->support_known = true;
}

// The new tractions (qx, qy on the loaded cells) into the cleared state.
void StoreTractions(const TaxelGrid& grid, const Cells& cells, const std::vector<double>& qx,
                    const std::vector<double>& qy, TangentialState* state) {
  ClearTractions(grid, state);
  CellBounds bounds;
  for (size_t c = 0; c < cells.index.size(); ++c) {
    const int k = cells.index[c];
    state->shear_x_pa[k] = qx[c];
    state->shear_y_pa[k] = qy[c];
    bounds.Add(k % grid.n, k / grid.n);
  }
  state->support = bounds.Box();
}

// q_c = Proj_{|q| <= g_c}(y_c + k lam): lam (2-D) such that sum_c q_c =
// (tx, ty), by Newton's method with backtracking on the convex potential
// Phi(lam) = sum psi(y + k lam) / k - t . lam, whose gradient is sum q - t.
// Requires |t| < sum g (a solution exists). Then the round-off residual of
// the sum goes evenly to the cells inside their disks. slip[c] = 1 where the
// projection clipped. Returns the Newton steps taken.
int ProjectWithForce(const std::vector<double>& yx, const std::vector<double>& yy,
                     const std::vector<double>& g, double k, double tx, double ty, double* lam_x,
                     double* lam_y, std::vector<double>* qx, std::vector<double>* qy,
                     std::vector<unsigned char>* slip) {
  const size_t m = g.size();
  qx->resize(m);
  qy->resize(m);
  slip->resize(m);
  double lx = *lam_x, ly = *lam_y;
  double g_sum = 0;
  for (size_t c = 0; c < m; ++c) g_sum += g[c];
  const double scale = g_sum + std::hypot(tx, ty);
  // Phi(lam) and, with `grad`, its gradient and Hessian, in one pass; psi,
  // the potential of the projection onto the disk |q| <= g, is |t|^2 / 2
  // inside and g |t| - g^2 / 2 outside (its gradient is the projection).
  struct Eval {
    double phi = 0, gx = 0, gy = 0, hxx = 0, hxy = 0, hyy = 0;
  };
  auto eval = [&](double ax, double ay, bool grad) {
    double phi = 0, sx = 0, sy = 0, h11 = 0, h12 = 0, h22 = 0;
    for (size_t c = 0; c < m; ++c) {
      const double px = yx[c] + k * ax, py = yy[c] + k * ay;
      const double t2 = px * px + py * py;
      if (t2 <= g[c] * g[c]) {  // psi = |t|^2 / 2, its gradient t
        phi += 0.5 * t2;
        if (!grad) continue;
        sx += px;
        sy += py;
        h11 += 1.0;
        h22 += 1.0;
      } else {  // psi = g |t| - g^2 / 2, its gradient g t / |t|
        const double t = std::sqrt(t2);
        phi += g[c] * t - 0.5 * g[c] * g[c];
        if (!grad) continue;
        const double inv = 1.0 / t, f = g[c] * inv;
        sx += f * px;
        sy += f * py;
        const double ux = px * inv, uy = py * inv;
        h11 += f * (1.0 - ux * ux);
        h12 -= f * ux * uy;
        h22 += f * (1.0 - uy * uy);
      }
    }
    Eval e;
    e.phi = phi / k - tx * ax - ty * ay;
    e.gx = sx - tx;
    e.gy = sy - ty;
    e.hxx = k * h11;
    e.hxy = k * h12;
    e.hyy = k * h22;
    return e;
  };
  int steps = 0;
  double last_norm = HUGE_VAL;
  // Each step's trial point is evaluated with its gradient, which the next
  // step then starts from (one pass per accepted full step).
  Eval cur = eval(lx, ly, true);
  for (; steps < 60; ++steps) {
    const double phi = cur.phi, gx = cur.gx, gy = cur.gy;
    // Close enough (the rest goes to the stick cells below), or stalled.
    const double norm = std::hypot(gx, gy);
    if (norm <= 1e-10 * scale || (norm <= 1e-8 * scale && norm > 0.5 * last_norm)) break;
    last_norm = norm;
    // Regularised so that a step exists when every cell slips the same way.
    const double reg = 1e-12 * k * static_cast<double>(m);
    const double hxx = cur.hxx + reg, hyy = cur.hyy + reg, hxy = cur.hxy;
    const double det = hxx * hyy - hxy * hxy;
    const double dx = -(hyy * gx - hxy * gy) / det, dy = -(hxx * gy - hxy * gx) / det;
    const double slope = gx * dx + gy * dy;
    // Phi's round-off (~1e-16 of its terms) hides decreases below ~1e-12 of
    // it: near the solution Armijo cannot tell, and Newton is then exact
    // (piecewise quadratic, one piece).
    const bool flat = -slope <= 1e-12 * (std::fabs(phi) + g_sum * g_sum / k);
    const Eval full = eval(lx + dx, ly + dy, true);
    if (flat || full.phi <= phi + 1e-4 * slope) {
      lx += dx;
      ly += dy;
      cur = full;
      continue;
    }
    double s = 1.0;
    bool accepted = false;
    for (int b = 1; b < 40; ++b) {
      s *= 0.5;
      if (eval(lx + s * dx, ly + s * dy, false).phi <= phi + 1e-4 * s * slope) {
        accepted = true;
        break;
      }
    }
    if (!accepted) {
      // Phi flat to round-off along d: take the Newton step if it shrinks
      // the gradient, else stop.
      if (std::hypot(full.gx, full.gy) >= norm) break;
      lx += dx;
      ly += dy;
      cur = full;
      continue;
    }
    lx += s * dx;
    ly += s * dy;
    cur = eval(lx, ly, true);
  }
  double sx = 0, sy = 0;
  int inside = 0;
  for (size_t c = 0; c < m; ++c) {
    const double px = yx[c] + k * lx, py = yy[c] + k * ly;
    const double t2 = px * px + py * py;
    if (t2 <= g[c] * g[c]) {
      (*qx)[c] = px;
      (*qy)[c] = py;
      (*slip)[c] = 0;
      ++inside;
    } else {
      const double f = g[c] / std::sqrt(t2);
      (*qx)[c] = f * px;
      (*qy)[c] = f * py;
      (*slip)[c] = 1;
    }
    sx += (*qx)[c];
    sy += (*qy)[c];
  }
  if (inside > 0) {
    const double ex = (tx - sx) / inside, ey = (ty - sy) / inside;
    for (size_t c = 0; c < m; ++c)
      if (!(*slip)[c]) {
        (*qx)[c] += ex;
        (*qy)[c] += ey;
      }
  } else if (g_sum > 0) {
    // Every cell slips (|t| just below sum g): Newton's residual, up to
    // 1e-8 of the load, goes to all cells in proportion to their disks.
    const double ex = (tx - sx) / g_sum, ey = (ty - sy) / g_sum;
    for (size_t c = 0; c < m; ++c) {
      (*qx)[c] += g[c] * ex;
      (*qy)[c] += g[c] * ey;
    }
  }
  *lam_x = lx;
  *lam_y = ly;
  return steps;
}

// Full slip (|F| >= mu P) or no load: q = p F / P on the loaded cells.
void FullSlip(const TaxelGrid& grid, const std::vector<double>& pressure_pa, const Cells& cells,
              double fx_n, double fy_n, TangentialState* state, TangentialResult* result) {
  const size_t N = grid.Size();
  std::vector<double> qx(cells.index.size()), qy(cells.index.size());
  if (cells.pressure_sum > 0.0) {
    const double force_per_pa = cells.pressure_sum * grid.Area();
    const double rx = fx_n / force_per_pa, ry = fy_n / force_per_pa;
    for (size_t c = 0; c < cells.index.size(); ++c) {
      qx[c] = rx * pressure_pa[cells.index[c]];
      qy[c] = ry * pressure_pa[cells.index[c]];
    }
  }
  StoreTractions(grid, cells, qx, qy, state);
  result->stick.assign(N, 0);
  result->loaded_cells = static_cast<int>(cells.index.size());
  result->stick_cells = 0;
  result->stuck_share = 0;
  result->full_slip = !cells.index.empty();
}

void Finish(const Cells& cells, const std::vector<unsigned char>& slip, size_t N,
            TangentialResult* result) {
  result->stick.assign(N, 0);
  result->loaded_cells = static_cast<int>(cells.index.size());
  result->stick_cells = 0;
  for (size_t c = 0; c < cells.index.size(); ++c)
    if (!slip[c]) {
      result->stick[cells.index[c]] = 1;
      ++result->stick_cells;
    }
  result->stuck_share = result->loaded_cells > 0
                            ? static_cast<double>(result->stick_cells) / result->loaded_cells
                            : 0.0;
  result->full_slip = false;
}

}  // namespace

TangentialCompliance::TangentialCompliance(double young_pa, double poisson, double pitch_m, int n)
    : n_(n), pitch_m_(pitch_m) {
  const double G = young_pa / (2.0 * (1.0 + poisson));
  const double c = 1.0 / (2.0 * kPi * G);
  const size_t L = 2 * static_cast<size_t>(n) - 1;
  kxx_.resize(L * L);
  kyy_.resize(L * L);
  kxy_.resize(L * L);
  for (int dj = -(n - 1); dj <= n - 1; ++dj)
    for (int di = -(n - 1); di <= n - 1; ++di) {
      const double x = di * pitch_m, y = dj * pitch_m;
      const double a = CornerSum(PrimA, x, y, pitch_m), b = CornerSum(PrimB, x, y, pitch_m);
      const double r = CornerSum(PrimR, x, y, pitch_m);
      const size_t k = static_cast<size_t>(dj + n - 1) * L + (di + n - 1);
      kxx_[k] = c * ((1.0 - poisson) * a + b);
      kyy_[k] = c * (a + (1.0 - poisson) * b);
      kxy_[k] = c * poisson * r;
    }
}

std::shared_ptr<const TangentialCompliance::Spectra> TangentialCompliance::SpectraFor(
    int bx, int by) const {
  const int mx = NextFftSize(2 * bx - 1), my = NextFftSize(2 * by - 1);
  std::lock_guard<std::mutex> lock(mu_);
  auto& slot = spectra_[{mx, my}];
  if (slot) return slot;
  auto s = std::make_shared<Spectra>(mx, my);
  const double norm = 1.0 / (static_cast<double>(mx) * my);
  std::vector<double> kr(static_cast<size_t>(mx) * my), sre(s->fft.spectrum_size()),
      sim(s->fft.spectrum_size()), scratch;
  // Each kernel wrapped onto the torus (offsets up to the box's reach do
  // not wrap); K(-d) = K(d) for all three (xy is odd in x and in y), so the
  // transforms are real. The xy kernel is left zero on a Nyquist row or
  // column, where +d and -d share a point.
  auto spectrum = [&](const std::vector<double>& table, bool odd, std::vector<double>* out) {
    std::fill(kr.begin(), kr.end(), 0.0);
    for (int y = 0; y < my; ++y) {
      const int dy = y <= my / 2 ? y : y - my;
      if (std::abs(dy) > n_ - 1 || (odd && 2 * y == my)) continue;
      for (int x = 0; x < mx; ++x) {
        const int dx = x <= mx / 2 ? x : x - mx;
        if (std::abs(dx) > n_ - 1 || (odd && 2 * x == mx)) continue;
        kr[static_cast<size_t>(y) * mx + x] = At(table, dx, dy);
      }
    }
    s->fft.Forward(kr.data(), nullptr, mx, my, mx, sre.data(), sim.data(), &scratch);
    out->resize(sre.size());
    for (size_t k = 0; k < sre.size(); ++k) (*out)[k] = sre[k] * norm;
  };
  spectrum(kxx_, false, &s->xx);
  spectrum(kyy_, false, &s->yy);
  spectrum(kxy_, true, &s->xy);
  s->xx_f.assign(s->xx.begin(), s->xx.end());
  s->yy_f.assign(s->yy.begin(), s->yy.end());
  s->xy_f.assign(s->xy.begin(), s->xy.end());
  slot = std::move(s);
  return slot;
}

const TangentialCompliance::LocalInverse& TangentialCompliance::local_inverse() const {
  std::call_once(local_inverse_once_, [this] {
    // The inverse operator's symbol (the 2 x 2 inverse of K's at every
    // frequency) on the torus of the whole grid's reach, back to offsets.
    const auto s = SpectraFor(n_, n_);
    const Fft2D& fft = s->fft;
    const int mx = fft.nx(), my = fft.ny();
    const size_t S = fft.spectrum_size();
    std::vector<double> ixx(S), iyy(S), ixy(S), zero(S), scratch;
    // The kernels cut off at the grid's reach ring at high frequencies,
    // where the symbol can dip to zero: floored at 1e-3 of its largest.
    const double floor = 1e-3 * std::max(s->xx[0], s->yy[0]);
    for (size_t k = 0; k < S; ++k) {
      const double a = std::max(s->xx[k], floor), b = std::max(s->yy[k], floor);
      const double c = std::clamp(s->xy[k], -0.9 * std::sqrt(a * b), 0.9 * std::sqrt(a * b));
      const double det = a * b - c * c;
      ixx[k] = b / det;
      iyy[k] = a / det;
      ixy[k] = -c / det;
    }
    // s holds K's symbol / (mx my) and InverseReal has no 1 / (mx my).
    const double norm = 1.0 / (static_cast<double>(mx) * my * mx * my);
    std::vector<double> out(static_cast<size_t>(mx) * my);
    auto centre = [&](std::vector<double>* spec, std::array<double, 9>* st) {
      std::fill(zero.begin(), zero.end(), 0.0);
      fft.InverseReal(spec->data(), zero.data(), my, mx, out.data(), mx, &scratch);
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di)
          (*st)[(dj + 1) * 3 + di + 1] =
              out[static_cast<size_t>((dj + my) % my) * mx + (di + mx) % mx] * norm;
    };
    LocalInverse li;
    centre(&ixx, &li.xx);
    centre(&iyy, &li.yy);
    centre(&ixy, &li.xy);
    // The truncated stencils' symbols (all even: sum s(d) cos(k . d)) must
    // stay positive definite.
    auto definite = [&](bool with_xy) {
      for (int u = 0; u < 64; ++u)
        for (int v = 0; v < 64; ++v) {
          double a = 0, b = 0, c = 0;
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              const double w = std::cos(2 * kPi * (u * di + v * dj) / 64.0);
              const int k = (dj + 1) * 3 + di + 1;
              a += li.xx[k] * w;
              b += li.yy[k] * w;
              c += with_xy ? li.xy[k] * w : 0.0;
            }
          if (!(a > 0) || !(b > 0) || !(a * b - c * c > 0)) return false;
        }
      return true;
    };
    if (!definite(true)) {
      li.xy.fill(0.0);
      if (!definite(false)) return;
    }
    li.empty = false;
    local_inverse_ = li;
  });
  return local_inverse_;
}

namespace {

template <typename T>
void ApplyIn(const Fft2D& fft, const std::vector<T>& kxx, const std::vector<T>& kyy,
             const std::vector<T>& kxy, const double* qx, const double* qy, int bx, int by,
             double* ux, double* uy, std::vector<T>* sxr, std::vector<T>* sxi, std::vector<T>* syr,
             std::vector<T>* syi, std::vector<T>* scratch) {
  const size_t S = fft.spectrum_size();
  sxr->resize(S);
  sxi->resize(S);
  syr->resize(S);
  syi->resize(S);
  fft.ForwardReal(qx, bx, by, bx, sxr->data(), sxi->data(), scratch);
  fft.ForwardReal(qy, bx, by, bx, syr->data(), syi->data(), scratch);
  T* __restrict ar = sxr->data();
  T* __restrict ai = sxi->data();
  T* __restrict br = syr->data();
  T* __restrict bi = syi->data();
  for (size_t k = 0; k < S; ++k) {
    const T xr = ar[k], xi = ai[k], yr = br[k], yi = bi[k];
    ar[k] = kxx[k] * xr + kxy[k] * yr;
    ai[k] = kxx[k] * xi + kxy[k] * yi;
    br[k] = kxy[k] * xr + kyy[k] * yr;
    bi[k] = kxy[k] * xi + kyy[k] * yi;
  }
  fft.InverseReal(ar, ai, by, bx, ux, bx, scratch);
  fft.InverseReal(br, bi, by, bx, uy, bx, scratch);
}

}  // namespace

void TangentialCompliance::Apply(const Spectra& s, const double* qx, const double* qy, int bx,
                                 int by, double* ux, double* uy, Work* w,
                                 ApplyPrecision precision) const {
  if (precision == ApplyPrecision::kFloat)
    ApplyIn(s.fft, s.xx_f, s.yy_f, s.xy_f, qx, qy, bx, by, ux, uy, &w->sxr_f, &w->sxi_f, &w->syr_f,
            &w->syi_f, &w->scratch_f);
  else
    ApplyIn(s.fft, s.xx, s.yy, s.xy, qx, qy, bx, by, ux, uy, &w->sxr, &w->sxi, &w->syr, &w->syi,
            &w->scratch);
}

double WinklerTangentialStiffness(double normal_stiffness_pa_per_m, double poisson) {
  return normal_stiffness_pa_per_m * 2.0 * (1.0 - poisson) / (2.0 - poisson);
}

std::string CheckTangentialInputs(const TaxelGrid& grid, const std::vector<double>& pressure_pa,
                                  double mu, double fx_n, double fy_n, const TangentialState& state,
                                  const CellBox* pressure_box) {
  const size_t N = grid.Size();
  if (grid.n <= 0 || !(grid.pitch_m > 0))
    return "grid: n = " + std::to_string(grid.n) + ", pitch_m = " + Num(grid.pitch_m) +
           " must be > 0";
  if (pressure_pa.size() != N)
    return "pressure_pa has " + std::to_string(pressure_pa.size()) + " cells, the grid " +
           std::to_string(N);
  const CellBox box = ScanBox(grid, pressure_box);
  if (box.i0 < 0 || box.j0 < 0 || box.i0 + box.nx > grid.n || box.j0 + box.ny > grid.n)
    return "pressure box [" + std::to_string(box.i0) + ", " + std::to_string(box.i0 + box.nx) +
           ") x [" + std::to_string(box.j0) + ", " + std::to_string(box.j0 + box.ny) +
           ") must lie in the grid [0, " + std::to_string(grid.n) + ")^2";
  for (int j = box.j0; j < box.j0 + box.ny; ++j)
    for (int i = box.i0; i < box.i0 + box.nx; ++i) {
      const double p = pressure_pa[static_cast<size_t>(j) * grid.n + i];
      if (!std::isfinite(p) || p < 0) return "pressure_pa must be finite and >= 0, got " + Num(p);
    }
  if (!std::isfinite(mu) || mu < 0) return "friction mu = " + Num(mu) + " must be finite, >= 0";
  if (!std::isfinite(fx_n) || !std::isfinite(fy_n))
    return "tangential force (" + Num(fx_n) + ", " + Num(fy_n) + ") N must be finite";
  const bool empty = state.shear_x_pa.empty() && state.shear_y_pa.empty();
  if (!empty && (state.shear_x_pa.size() != N || state.shear_y_pa.size() != N))
    return "state tractions must be empty or have the grid's " + std::to_string(N) + " cells";
  if (!std::isfinite(state.shift_x_m) || !std::isfinite(state.shift_y_m))
    return "state shift must be finite";
  return "";
}

bool SolveTangentialWinkler(const TaxelGrid& grid, const std::vector<double>& pressure_pa,
                            double mu, double fx_n, double fy_n,
                            double tangential_stiffness_pa_per_m, TangentialState* state,
                            TangentialResult* result, std::string* error,
                            const CellBox* pressure_box) {
  std::string e = CheckTangentialInputs(grid, pressure_pa, mu, fx_n, fy_n, *state, pressure_box);
  if (e.empty() &&
      !(tangential_stiffness_pa_per_m > 0 && std::isfinite(tangential_stiffness_pa_per_m)))
    e = "tangential stiffness " + Num(tangential_stiffness_pa_per_m) + " Pa/m must be > 0";
  if (!e.empty()) {
    if (error) *error = "tangential (winkler): " + e;
    return false;
  }
  const size_t N = grid.Size();
  const Cells cells = LoadedCells(grid, pressure_pa, mu, ScanBox(grid, pressure_box));
  const double tx = fx_n / grid.Area(), ty = fy_n / grid.Area();
  result->iterations = 0;
  result->projection_steps = 0;
  result->change = 0;
  if (cells.index.empty() || std::hypot(tx, ty) >= kFullSlipShare * cells.g_sum) {
    FullSlip(grid, pressure_pa, cells, fx_n, fy_n, state, result);
    return true;
  }
  const size_t m = cells.index.size();
  const bool have_prev = !state->shear_x_pa.empty();
  std::vector<double> yx(m, 0.0), yy(m, 0.0), qx, qy;
  if (have_prev)
    for (size_t c = 0; c < m; ++c) {
      yx[c] = state->shear_x_pa[cells.index[c]];
      yy[c] = state->shear_y_pa[cells.index[c]];
    }
  std::vector<unsigned char> slip;
  double dwx = 0, dwy = 0;
  result->iterations = result->projection_steps = ProjectWithForce(
      yx, yy, cells.g, tangential_stiffness_pa_per_m, tx, ty, &dwx, &dwy, &qx, &qy, &slip);
  StoreTractions(grid, cells, qx, qy, state);
  state->shift_x_m += dwx;
  state->shift_y_m += dwy;
  Finish(cells, slip, N, result);
  return true;
}

bool SolveTangentialElastic(const TaxelGrid& grid, const std::vector<double>& pressure_pa,
                            double mu, double fx_n, double fy_n, const TangentialCompliance& K,
                            double tolerance, int max_iterations, TangentialState* state,
                            TangentialResult* result, std::string* error, ApplyPrecision precision,
                            const CellBox* pressure_box) {
  std::string e = CheckTangentialInputs(grid, pressure_pa, mu, fx_n, fy_n, *state, pressure_box);
  if (e.empty() && (K.n() != grid.n || K.pitch_m() != grid.pitch_m))
    e = "compliance built for n = " + std::to_string(K.n()) + ", pitch " + Num(K.pitch_m()) +
        " m, not the grid's";
  if (e.empty() && !(tolerance > 0 && tolerance < 1))
    e = "tolerance " + Num(tolerance) + " must be in (0, 1)";
  if (e.empty() && max_iterations < 1)
    e = "max_iterations " + std::to_string(max_iterations) + " must be >= 1";
  if (!e.empty()) {
    if (error) *error = "tangential (elastic): " + e;
    return false;
  }
  const size_t N = grid.Size();
  const int n = grid.n;
  const Cells cells = LoadedCells(grid, pressure_pa, mu, ScanBox(grid, pressure_box));
  const double tx = fx_n / grid.Area(), ty = fy_n / grid.Area();
  result->iterations = 0;
  result->projection_steps = 0;
  result->change = 0;
  if (cells.index.empty() || std::hypot(tx, ty) >= kFullSlipShare * cells.g_sum) {
    FullSlip(grid, pressure_pa, cells, fx_n, fy_n, state, result);
    return true;
  }
  const size_t m = cells.index.size();
  const bool have_prev = !state->shear_x_pa.empty();
  // The box: the loaded cells and the last step's tractions (their
  // removal moves the surface too).
  CellBounds bounds;
  for (int k : cells.index) bounds.Add(k % n, k / n);
  if (have_prev && state->support_known) {
    if (!state->support.empty()) {
      const CellBox& b = state->support;
      bounds.AddRow(b.i0, b.i0 + b.nx - 1, b.j0);
      bounds.AddRow(b.i0, b.i0 + b.nx - 1, b.j0 + b.ny - 1);
    }
  } else if (have_prev) {
    for (int j = 0; j < n; ++j) {
      const double* sx = state->shear_x_pa.data() + static_cast<size_t>(j) * n;
      const double* sy = state->shear_y_pa.data() + static_cast<size_t>(j) * n;
      int lo = 0, hi = n - 1;
      while (lo < n && sx[lo] == 0.0 && sy[lo] == 0.0) ++lo;
      if (lo == n) continue;
      while (sx[hi] == 0.0 && sy[hi] == 0.0) --hi;
      bounds.AddRow(lo, hi, j);
    }
  }
  const CellBox box = bounds.Box();
  const int bx = box.nx, by = box.ny;
  const size_t B = static_cast<size_t>(bx) * by;
  auto box_index = [&](int k) {
    return static_cast<size_t>(k / n - box.j0) * bx + (k % n - box.i0);
  };
  std::vector<size_t> cb(m);
  for (size_t c = 0; c < m; ++c) cb[c] = box_index(cells.index[c]);
  std::vector<double> pqx(B, 0.0), pqy(B, 0.0);
  if (have_prev)
    for (int j = 0; j < by; ++j)
      for (int i = 0; i < bx; ++i) {
        const size_t k = static_cast<size_t>(box.j0 + j) * n + box.i0 + i;
        pqx[static_cast<size_t>(j) * bx + i] = state->shear_x_pa[k];
        pqy[static_cast<size_t>(j) * bx + i] = state->shear_y_pa[k];
      }
  const auto spectra = K.SpectraFor(bx, by);
  TangentialCompliance::Work work;

  // Warm start: the last tractions on today's cells, projected onto the
  // disks with the force restored.
  std::vector<double> yx(m), yy(m), qx, qy;
  for (size_t c = 0; c < m; ++c) {
    yx[c] = pqx[cb[c]];
    yy[c] = pqy[cb[c]];
  }
  std::vector<unsigned char> slip;
  double lx = 0, ly = 0;
  int projection_steps = ProjectWithForce(yx, yy, cells.g, 1.0, tx, ty, &lx, &ly, &qx, &qy, &slip);
  // The relative change of q so far (here the warm start's), which sets the
  // next Newton step's CG tolerance.
  double change = 0;
  {
    double diff = 0, norm = 0;
    for (size_t c = 0; c < m; ++c) {
      diff += std::fabs(qx[c] - yx[c]) + std::fabs(qy[c] - yy[c]);
      norm += std::fabs(qx[c]) + std::fabs(qy[c]);
    }
    change = norm > 0 ? std::min(1.0, diff / norm) : 1.0;
  }

  std::vector<double> dx(B), dy(B), rx(B), ry(B), tbx(B, 0.0), tby(B, 0.0), wx(B), wy(B);
  std::vector<double> tcx(m, 0.0), tcy(m, 0.0), oldx(m), oldy(m);
  // r = K (q - q_prev) on the box: the surface's tangential displacement
  // since the last step.
  auto residual = [&]() {
    for (size_t b = 0; b < B; ++b) {
      dx[b] = -pqx[b];
      dy[b] = -pqy[b];
    }
    for (size_t c = 0; c < m; ++c) {
      dx[cb[c]] += qx[c];
      dy[cb[c]] += qy[c];
    }
    K.Apply(*spectra, dx.data(), dy.data(), bx, by, rx.data(), ry.data(), &work, precision);
  };
  // The shift increment: the stick cells' mean displacement (all cells'
  // when none sticks).
  auto shift_increment = [&](double* wxm, double* wym) {
    double sx = 0, sy = 0, ax = 0, ay = 0;
    int count = 0;
    for (size_t c = 0; c < m; ++c) {
      ax += rx[cb[c]];
      ay += ry[cb[c]];
      if (!slip[c]) {
        sx += rx[cb[c]];
        sy += ry[cb[c]];
        ++count;
      }
    }
    if (count > 0) {
      *wxm = sx / count;
      *wym = sy / count;
    } else {
      *wxm = ax / m;
      *wym = ay / m;
    }
  };
  // Active-set iterations: a semismooth Newton step on the current sets
  // (NewtonCg), solved by conjugate gradients until q changes by less than
  // the tolerance; then one projected step of every cell (stick cells whose
  // traction passes mu p start slipping, slip cells stick where their slip
  // reverses) with the force restored. Done when that step changes q by
  // less than the tolerance. Every CG iteration and every step costs one
  // compliance application.
  residual();
  double tau_ref = 0;
  int it = 0;
  auto l1 = [&]() {
    double norm = 0;
    for (size_t c = 0; c < m; ++c) norm += std::fabs(qx[c]) + std::fabs(qy[c]);
    return norm;
  };
  // The Newton step: stick cells free (both components, r = w), slip cells
  // free across their traction's direction e only, q = g e + a e_perp
  // linearised about the disk's edge: the slip law q || (w - r) gives
  // (r - w) . e_perp + (s / g) a = 0 with s = (w - r) . e, the slip along e,
  // which adds s / g to the operator (still symmetric positive). Projected
  // CG on that subspace with the force kept (the changes sum to zero); the
  // slip cells turn with their neighbours in one solve, where projected
  // steps of their own converged linearly.
  std::vector<double> px(m), py(m), dcoef(m), ax(m), ay(m);
  const TangentialCompliance::LocalInverse& local = K.local_inverse();
  // (the preconditioner's padded box; zero but for the loaded cells)
  std::vector<double> pad_x(local.empty ? 0 : static_cast<size_t>(bx + 2) * (by + 2), 0.0),
      pad_y(pad_x.size(), 0.0);
  auto NewtonCg = [&](double cg_tolerance) {
    // The shift: least squares over the free components.
    double m11 = 0, m12 = 0, m22 = 0;
    int stick_count = 0;
    for (size_t c = 0; c < m; ++c) {
      if (!slip[c]) {
        px[c] = py[c] = 0;
        dcoef[c] = 0;
        m11 += 1;
        m22 += 1;
        ++stick_count;
      } else {
        const double qn = std::hypot(qx[c], qy[c]);
        px[c] = qn > 0 ? -qy[c] / qn : 0.0;  // e_perp
        py[c] = qn > 0 ? qx[c] / qn : 0.0;
        dcoef[c] = 0;
        m11 += px[c] * px[c];
        m12 += px[c] * py[c];
        m22 += py[c] * py[c];
      }
      ax[c] = ay[c] = 0;  // the slip cells' change across e this step
    }
    if (stick_count == 0) return;
    const double det = m11 * m22 - m12 * m12;
    // P_c v: the cell's free part of v.
    auto free_part = [&](size_t c, double vx, double vy, double* ox, double* oy) {
      if (!slip[c]) {
        *ox = vx;
        *oy = vy;
      } else {
        const double d = vx * px[c] + vy * py[c];
        *ox = d * px[c];
        *oy = d * py[c];
      }
    };
    // Projection onto the subspace: v_c <- v_c - P_c M^-1 sum v (v free already).
    auto project = [&](std::vector<double>* vx, std::vector<double>* vy) {
      double sx = 0, sy = 0;
      for (size_t c = 0; c < m; ++c) {
        sx += (*vx)[c];
        sy += (*vy)[c];
      }
      const double lx = (m22 * sx - m12 * sy) / det, ly = (m11 * sy - m12 * sx) / det;
      for (size_t c = 0; c < m; ++c) {
        double fx, fy;
        free_part(c, lx, ly, &fx, &fy);
        (*vx)[c] -= fx;
        (*vy)[c] -= fy;
      }
    };
    {  // the slip rate along e for the operator's diagonal: s / g (>= 0)
      double sx = 0, sy = 0;
      for (size_t c = 0; c < m; ++c) {
        double fx, fy;
        free_part(c, rx[cb[c]], ry[cb[c]], &fx, &fy);
        sx += fx;
        sy += fy;
      }
      const double wxm = (m22 * sx - m12 * sy) / det, wym = (m11 * sy - m12 * sx) / det;
      for (size_t c = 0; c < m; ++c)
        if (slip[c] && cells.g[c] > 0) {
          const double sl =
              ((wxm - rx[cb[c]]) * qx[c] + (wym - ry[cb[c]]) * qy[c]) / (cells.g[c] * cells.g[c]);
          dcoef[c] = std::max(sl, 0.0);
        }
    }
    // The preconditioner: v = P L P z with L the local inverse of K (P the
    // projection onto the subspace), once the first (steepest-descent)
    // step has set tau_ref.
    auto precondition = [&](const std::vector<double>& zx, const std::vector<double>& zy,
                            std::vector<double>* vx, std::vector<double>* vy) {
      // z on the box with a ring of zeros, so that every cell's 3 x 3
      // neighbourhood is in it
      const int px_stride = bx + 2;
      for (size_t c = 0; c < m; ++c) {
        const size_t b = cb[c] + (cb[c] / bx) * 2 + px_stride + 1;
        pad_x[b] = zx[c];
        pad_y[b] = zy[c];
      }
      const long off[9] = {-px_stride - 1, -px_stride, -px_stride + 1, -1, 0, 1,
                           px_stride - 1,  px_stride,  px_stride + 1};
      for (size_t c = 0; c < m; ++c) {
        const size_t b = cb[c] + (cb[c] / bx) * 2 + px_stride + 1;
        double sx = 0, sy = 0;
        for (int k = 0; k < 9; ++k) {
          const double ux = pad_x[b + off[k]], uy = pad_y[b + off[k]];
          sx += local.xx[k] * ux + local.xy[k] * uy;
          sy += local.xy[k] * ux + local.yy[k] * uy;
        }
        free_part(c, sx, sy, &(*vx)[c], &(*vy)[c]);
      }
      project(vx, vy);
    };
    std::vector<double> zx(m), zy(m), vx(m), vy(m);
    double gg_old = 0;
    bool first = true;
    while (it < max_iterations) {
      for (size_t c = 0; c < m; ++c) {
        free_part(c, rx[cb[c]], ry[cb[c]], &zx[c], &zy[c]);
        zx[c] += dcoef[c] * ax[c];
        zy[c] += dcoef[c] * ay[c];
      }
      project(&zx, &zy);
      const bool preconditioned = !local.empty && tau_ref > 0.0;
      if (preconditioned) {
        precondition(zx, zy, &vx, &vy);
      } else {
        vx = zx;
        vy = zy;
      }
      double gg = 0;
      for (size_t c = 0; c < m; ++c) gg += zx[c] * vx[c] + zy[c] * vy[c];
      if (!(gg > 0)) break;
      const double beta = first ? 0.0 : gg / gg_old;
      // (the steepest-descent step before the preconditioned ones restarts)
      first = !preconditioned && !local.empty;
      gg_old = gg;
      for (size_t c = 0; c < m; ++c) {
        tcx[c] = vx[c] + beta * tcx[c];
        tcy[c] = vy[c] + beta * tcy[c];
      }
      std::fill(tbx.begin(), tbx.end(), 0.0);
      std::fill(tby.begin(), tby.end(), 0.0);
      for (size_t c = 0; c < m; ++c) {
        tbx[cb[c]] = tcx[c];
        tby[cb[c]] = tcy[c];
      }
      K.Apply(*spectra, tbx.data(), tby.data(), bx, by, wx.data(), wy.data(), &work, precision);
      ++it;
      double tw = 0, tg = 0, step = 0;
      for (size_t c = 0; c < m; ++c) {
        tw += tcx[c] * wx[cb[c]] + tcy[c] * wy[cb[c]] +
              dcoef[c] * (tcx[c] * tcx[c] + tcy[c] * tcy[c]);
        tg += tcx[c] * zx[c] + tcy[c] * zy[c];
        step += std::fabs(tcx[c]) + std::fabs(tcy[c]);
      }
      if (!(tw > 0) || !(tg > 0)) break;
      const double tau = tg / tw;
      if (tau_ref == 0.0) tau_ref = tau;
      for (size_t c = 0; c < m; ++c) {
        qx[c] -= tau * tcx[c];
        qy[c] -= tau * tcy[c];
        if (slip[c]) {
          ax[c] -= tau * tcx[c];
          ay[c] -= tau * tcy[c];
        }
      }
      for (size_t b = 0; b < B; ++b) {
        rx[b] -= tau * wx[b];
        ry[b] -= tau * wy[b];
      }
      const double norm = l1();
      if (!(norm > 0) || tau * step < cg_tolerance * norm) break;
    }
  };
  while (it < max_iterations) {
    NewtonCg(std::max(tolerance, kNewtonForcing * change));
    if (it >= max_iterations) break;
    // The projected step of every cell, by half the first steepest-descent
    // step (the Newton step turned the slip cells already; a longer step
    // overshoots their directions where the step is inexact).
    double dwx, dwy;
    shift_increment(&dwx, &dwy);
    const double tau_slip = 0.5 * (tau_ref > 0 ? tau_ref : 1.0 / K.Kxx(0, 0));
    for (size_t c = 0; c < m; ++c) {
      oldx[c] = qx[c];
      oldy[c] = qy[c];
      yx[c] = qx[c] - tau_slip * (rx[cb[c]] - dwx);
      yy[c] = qy[c] - tau_slip * (ry[cb[c]] - dwy);
    }
    lx = ly = 0;
    projection_steps += ProjectWithForce(yx, yy, cells.g, 1.0, tx, ty, &lx, &ly, &qx, &qy, &slip);
    double diff = 0;
    for (size_t c = 0; c < m; ++c) diff += std::fabs(qx[c] - oldx[c]) + std::fabs(qy[c] - oldy[c]);
    const double norm = l1();
    change = norm > 0 ? diff / norm : 0.0;
    // (cells that change sets without changing q, at the disk's edge with
    // no slip, do not hold it up; the shift below then reads the
    // displacement before this last step, which moved q by less than the
    // tolerance)
    if (change < tolerance) break;
    residual();
    ++it;
  }
  double dwx, dwy;
  shift_increment(&dwx, &dwy);
  // The box holds the old and the new tractions.
  if (have_prev) {
    state->support = box;
    state->support_known = true;
  }
  StoreTractions(grid, cells, qx, qy, state);
  state->shift_x_m += dwx;
  state->shift_y_m += dwy;
  result->iterations = it;
  result->projection_steps = projection_steps;
  result->change = change;
  Finish(cells, slip, N, result);
  return true;
}

}  // namespace mjtouch
