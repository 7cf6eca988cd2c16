#include "contact/pressure.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mjtouch {

const char* PressureModelName(PressureModel m) {
  switch (m) {
    case PressureModel::kContacts: return "contacts";
    case PressureModel::kWinkler: return "winkler";
    default: return "elastic";
  }
}

bool ParsePressureModel(const std::string& name, PressureModel* m) {
  for (PressureModel v : {PressureModel::kContacts, PressureModel::kWinkler,
                          PressureModel::kElastic}) {
    if (name == PressureModelName(v)) {
      *m = v;
      return true;
    }
  }
  return false;
}

namespace {

// Calls f(index) for every cell of the box, row by row.
template <typename F>
void ForBox(const TaxelGrid& grid, const CellBox& box, F&& f) {
  for (int j = box.j0; j < box.j0 + box.ny; ++j) {
    const size_t row = static_cast<size_t>(j) * grid.n;
    for (int i = box.i0; i < box.i0 + box.nx; ++i) f(row + i);
  }
}

}  // namespace

void ClearTraction(const TaxelGrid& grid, TractionField* f) {
  const size_t N = grid.Size();
  for (auto* v : {&f->pressure_pa, &f->shear_x_pa, &f->shear_y_pa}) {
    if (v->size() != N) v->assign(N, 0.0);
    else ForBox(grid, f->box, [&](size_t k) { (*v)[k] = 0.0; });
  }
  for (auto* v : {&f->pressure, &f->shear_x, &f->shear_y}) {
    if (v->size() != N) v->assign(N, 0.0f);
    else ForBox(grid, f->box, [&](size_t k) { (*v)[k] = 0.0f; });
  }
  f->box = CellBox{};
  f->runs.Clear();
  f->active_cells = 0;
  f->approach_m = 0.0;
}

bool NormalizeLoad(const TaxelGrid& grid, double force, TractionField* out) {
  double total = 0.0;
  ForBox(grid, out->box, [&](size_t k) { total += out->pressure_pa[k]; });
  if (!(total > 0.0) || !(force > 0.0)) {
    ForBox(grid, out->box, [&](size_t k) { out->pressure_pa[k] = 0.0; });
    return false;
  }
  const double scale = force / (grid.Area() * total);
  ForBox(grid, out->box, [&](size_t k) { out->pressure_pa[k] *= scale; });
  return true;
}

void FinishTraction(const TaxelGrid& grid, bool shear, TractionField* out) {
  const CellBox& b = out->box;
  ForBox(grid, b, [&](size_t k) {
    out->pressure[k] = static_cast<float>(out->pressure_pa[k]);
    out->shear_x[k] = shear ? static_cast<float>(out->shear_x_pa[k]) : 0.0f;
    out->shear_y[k] = shear ? static_cast<float>(out->shear_y_pa[k]) : 0.0f;
  });
  out->runs.Clear();
  out->active_cells = 0;
  for (int j = b.j0; j < b.j0 + b.ny; ++j) {
    int begin = -1;
    for (int i = b.i0; i <= b.i0 + b.nx; ++i) {
      bool on = false;
      if (i < b.i0 + b.nx) {
        const size_t idx = static_cast<size_t>(j) * grid.n + i;
        on = out->pressure_pa[idx] != 0.0 ||
             (shear && (out->shear_x_pa[idx] != 0.0 || out->shear_y_pa[idx] != 0.0));
        out->active_cells += on;
      }
      if (on && begin < 0) begin = i;
      if (!on && begin >= 0) {
        out->runs.row.push_back(j);
        out->runs.begin.push_back(begin);
        out->runs.end.push_back(i);
        begin = -1;
      }
    }
  }
}

bool SplatContacts(const TaxelGrid& grid, const std::vector<ContactPoint>& contacts,
                   TractionField* out) {
  ClearTraction(grid, out);
  const double inv_area = 1.0 / grid.Area();
  double total = 0.0;
  const int n = grid.n;
  int i_lo = n, i_hi = -1, j_lo = n, j_hi = -1;
  for (const ContactPoint& c : contacts) {
    // Fractional cell coordinates of the contact, clamped to the centres of
    // the outermost cells so that the whole force stays on the grid.
    const double top = n - 1;
    const double s = std::clamp(c.x_m / grid.pitch_m + 0.5 * top, 0.0, top);
    const double t = std::clamp(c.y_m / grid.pitch_m + 0.5 * top, 0.0, top);
    const int i0 = std::min(static_cast<int>(s), n - 2), j0 = std::min(static_cast<int>(t), n - 2);
    const double fs = s - i0, ft = t - j0;
    const double w[4] = {(1 - fs) * (1 - ft), fs * (1 - ft), (1 - fs) * ft, fs * ft};
    const size_t idx[4] = {static_cast<size_t>(j0) * n + i0, static_cast<size_t>(j0) * n + i0 + 1,
                           static_cast<size_t>(j0 + 1) * n + i0,
                           static_cast<size_t>(j0 + 1) * n + i0 + 1};
    for (int k = 0; k < 4; ++k) {
      out->pressure_pa[idx[k]] += w[k] * c.force_n[2] * inv_area;
      out->shear_x_pa[idx[k]] += w[k] * c.force_n[0] * inv_area;
      out->shear_y_pa[idx[k]] += w[k] * c.force_n[1] * inv_area;
    }
    i_lo = std::min(i_lo, i0);
    i_hi = std::max(i_hi, i0 + 1);
    j_lo = std::min(j_lo, j0);
    j_hi = std::max(j_hi, j0 + 1);
    total += c.force_n[2];
  }
  if (i_hi >= 0) out->box = CellBox{i_lo, j_lo, i_hi - i_lo + 1, j_hi - j_lo + 1};
  return total > 0.0;
}

bool WinklerPressure(const TaxelGrid& grid, const std::vector<double>& gap,
                     const std::vector<double>& cov, const CellBox& box, double k, double force,
                     double guess, TractionField* out) {
  // The same solve as WinklerPressureReference, value for value: the same
  // sums over the same terms in the same order, only fewer passes over the
  // cells that cannot touch. Newton's iterate only decreases, so after the
  // first evaluation at c0 every later pass skips the candidates with gap
  // >= c0 (their terms are skipped by `d > 0` anyway), and the load is
  // normalised over the touching cells alone (the others add exact zeros).
  ClearTraction(grid, out);
  const double A = grid.Area();
  const double target = force / (k * A);
  std::vector<double>& cg = out->scratch_gap;
  std::vector<double>& cc = out->scratch_cov;
  std::vector<size_t>& ci = out->scratch_index;
  const size_t cells = box.empty() ? 0 : static_cast<size_t>(box.nx) * box.ny;
  // All candidates, then (from index M on) the ones below c0.
  cg.resize(2 * cells);
  cc.resize(2 * cells);
  ci.resize(2 * cells);
  size_t M = 0;
  double gmin = std::numeric_limits<double>::infinity();
  double covmax = 0.0;
  for (int j = box.j0; j < box.j0 + box.ny; ++j) {
    const size_t row = static_cast<size_t>(j) * grid.n;
    for (size_t i = row + box.i0; i < row + box.i0 + box.nx; ++i) {
      if (cov[i] > 0.0 && std::isfinite(gap[i])) {
        cg[M] = gap[i];
        cc[M] = cov[i];
        ci[M] = i;
        ++M;
        gmin = std::min(gmin, gap[i]);
        covmax = std::max(covmax, cov[i]);
      }
    }
  }
  if (!std::isfinite(gmin) || !(force > 0.0)) return false;
  double* const g_all = cg.data();
  double* const c_all = cc.data();
  double* const g_low = g_all + M;
  double* const c_low = c_all + M;
  size_t* const i_low = ci.data() + M;
  size_t L = 0;
  // f(c) and its slope over the first m candidates of (g, w), in order.
  auto eval = [&](const double* g, const double* w, size_t m, double c, double* slope) {
    double f = -target, sl = 0.0;
    for (size_t i = 0; i < m; ++i) {
      const double d = c - g[i];
      if (d > 0.0) { f += w[i] * d; sl += w[i]; }
    }
    *slope = sl;
    return f;
  };
  // The same over every candidate, keeping those below c (the only ones
  // that can touch at c or to its left).
  auto eval_all = [&](double c, double* slope) {
    double f = -target, sl = 0.0;
    L = 0;
    for (size_t i = 0; i < M; ++i) {
      const double d = c - g_all[i];
      if (d > 0.0) {
        f += c_all[i] * d;
        sl += c_all[i];
        g_low[L] = g_all[i];
        c_low[L] = c_all[i];
        i_low[L] = ci[i];
        ++L;
      }
    }
    *slope = sl;
    return f;
  };
  double c = gmin + target / std::max(covmax, 1e-12);
  double f, s;
  bool have = false;
  if (std::isfinite(guess) && guess > gmin) {
    f = eval_all(guess, &s);
    if (f >= 0.0) {
      c = guess;
      have = true;
    }
  }
  if (!have) f = eval_all(c, &s);
  const double c0 = c;
  for (int it = 0; it < 200; ++it) {
    if (f <= 0.0 || s <= 0.0) break;
    const double next = c - f / s;
    if (!(next < c)) break;
    c = next;
    if (it + 1 < 200) f = eval(g_low, c_low, L, c, &s);
  }
  // Closed form from the converged contact set (see the reference). It stays
  // at or below c0 up to round-off; above it, every candidate is read.
  for (int pass = 0; pass < 4; ++pass) {
    const bool low = c <= c0;
    const double* g = low ? g_low : g_all;
    const double* w = low ? c_low : c_all;
    const size_t m = low ? L : M;
    double sum_cov = 0.0, sum_cov_g = 0.0;
    for (size_t i = 0; i < m; ++i) {
      if (c - g[i] > 0.0) {
        sum_cov += w[i];
        sum_cov_g += w[i] * g[i];
      }
    }
    if (!(sum_cov > 0.0)) break;
    const double next = (target + sum_cov_g) / sum_cov;
    if (next == c) break;
    c = next;
  }
  out->box = box;
  out->approach_m = c;
  // Pressure and NormalizeLoad's sum over the touching cells, box order.
  const bool low = c <= c0;
  const double* g = low ? g_low : g_all;
  const double* w = low ? c_low : c_all;
  const size_t* idx = low ? i_low : ci.data();
  const size_t m = low ? L : M;
  double* p = out->pressure_pa.data();
  double total = 0.0;
  size_t touching = 0;
  for (size_t i = 0; i < m; ++i) {
    const double d = c - g[i];
    if (d > 0.0) {
      p[idx[i]] = w[i] * d;
      total += w[i] * d;
      i_low[touching++] = idx[i];  // reuses the low list, read at or after i
    }
  }
  if (!(total > 0.0) || !(force > 0.0)) {
    for (size_t i = 0; i < touching; ++i) p[i_low[i]] = 0.0;
    return false;
  }
  const double scale = force / (A * total);
  for (size_t i = 0; i < touching; ++i) p[i_low[i]] *= scale;
  return true;
}

bool WinklerPressureReference(const TaxelGrid& grid, const std::vector<double>& gap,
                     const std::vector<double>& cov, const CellBox& box, double k, double force,
                     double guess, TractionField* out) {
  ClearTraction(grid, out);
  const double A = grid.Area();
  // Solve f(c) = sum cov_i max(c - g_i, 0) - force / (k A) = 0 over the
  // candidates (packed once: every pass below reads them contiguously). f is
  // convex, piecewise linear and increasing, so Newton from the right of the
  // root converges monotonically in finitely many steps.
  const double target = force / (k * A);
  std::vector<double>& cg = out->scratch_gap;
  std::vector<double>& cc = out->scratch_cov;
  std::vector<size_t>& ci = out->scratch_index;
  cg.clear();
  cc.clear();
  ci.clear();
  double gmin = std::numeric_limits<double>::infinity();
  double covmax = 0.0;
  ForBox(grid, box, [&](size_t i) {
    if (cov[i] > 0.0 && std::isfinite(gap[i])) {
      cg.push_back(gap[i]);
      cc.push_back(cov[i]);
      ci.push_back(i);
      gmin = std::min(gmin, gap[i]);
      covmax = std::max(covmax, cov[i]);
    }
  });
  if (!std::isfinite(gmin) || !(force > 0.0)) return false;
  const size_t M = cg.size();
  auto eval = [&](double c, double* slope) {
    double f = -target, s = 0.0;
    for (size_t i = 0; i < M; ++i) {
      const double d = c - cg[i];
      if (d > 0.0) { f += cc[i] * d; s += cc[i]; }
    }
    *slope = s;
    return f;
  };
  // A point to the right of the root: the whole target on one cell.
  double c = gmin + target / std::max(covmax, 1e-12);
  if (std::isfinite(guess) && guess > gmin) {
    double s;
    if (eval(guess, &s) >= 0.0) c = guess;  // warm start if it is to the right
  }
  for (int it = 0; it < 200; ++it) {
    double s;
    const double f = eval(c, &s);
    if (f <= 0.0 || s <= 0.0) break;
    const double next = c - f / s;
    if (!(next < c)) break;
    c = next;
  }
  // Recompute c in closed form from the converged contact set, in a fixed
  // order, so the result does not depend on the warm start (bit-identical
  // outputs whatever the history): c = (target + sum cov g) / sum cov.
  for (int pass = 0; pass < 4; ++pass) {
    double sum_cov = 0.0, sum_cov_g = 0.0;
    for (size_t i = 0; i < M; ++i) {
      if (c - cg[i] > 0.0) {
        sum_cov += cc[i];
        sum_cov_g += cc[i] * cg[i];
      }
    }
    if (!(sum_cov > 0.0)) break;
    const double next = (target + sum_cov_g) / sum_cov;
    if (next == c) break;
    c = next;
  }
  // Exact normalisation removes the last round-off of the solve.
  out->box = box;
  for (size_t i = 0; i < M; ++i) {
    const double d = c - cg[i];
    if (d > 0.0) out->pressure_pa[ci[i]] = cc[i] * d;
  }
  out->approach_m = c;
  return NormalizeLoad(grid, force, out);
}

void UniformSlipShear(const TaxelGrid& grid, double fn, double fx, double fy,
                      TractionField* field) {
  const double rx = fn > 0.0 ? fx / fn : 0.0, ry = fn > 0.0 ? fy / fn : 0.0;
  ForBox(grid, field->box, [&](size_t i) {
    field->shear_x_pa[i] = rx * field->pressure_pa[i];
    field->shear_y_pa[i] = ry * field->pressure_pa[i];
  });
}

}  // namespace mjtouch
