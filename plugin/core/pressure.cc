#include "pressure.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mjtouch {

bool WinklerPressure(const TaxelGrid& grid, const std::vector<double>& gap,
                     const std::vector<double>& cov, double k, double force,
                     double guess, TractionField* out) {
  const size_t N = grid.Size();
  out->pressure.assign(N, 0.0f);
  out->runs.Clear();
  out->active_cells = 0;
  const double A = grid.Area();
  // Solve f(c) = sum cov_i max(c - g_i, 0) - force / (k A) = 0. f is convex,
  // piecewise linear and increasing, so Newton from the right of the root
  // converges monotonically in finitely many steps.
  const double target = force / (k * A);
  double gmin = std::numeric_limits<double>::infinity();
  double covmax = 0.0;
  for (size_t i = 0; i < N; ++i) {
    if (cov[i] > 0.0 && gap[i] < gmin) gmin = gap[i];
    covmax = std::max(covmax, cov[i]);
  }
  if (!std::isfinite(gmin) || !(force > 0.0)) return false;
  auto eval = [&](double c, double* slope) {
    double f = -target, s = 0.0;
    for (size_t i = 0; i < N; ++i) {
      const double d = c - gap[i];
      if (d > 0.0 && cov[i] > 0.0) { f += cov[i] * d; s += cov[i]; }
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
    for (size_t i = 0; i < N; ++i) {
      if (cov[i] > 0.0 && c - gap[i] > 0.0) {
        sum_cov += cov[i];
        sum_cov_g += cov[i] * gap[i];
      }
    }
    if (!(sum_cov > 0.0)) break;
    const double next = (target + sum_cov_g) / sum_cov;
    if (next == c) break;
    c = next;
  }
  // Exact normalisation removes the last round-off of the solve.
  double total = 0.0;
  for (size_t i = 0; i < N; ++i) {
    const double d = c - gap[i];
    if (d > 0.0 && cov[i] > 0.0) total += cov[i] * d;
  }
  if (!(total > 0.0)) return false;
  const double scale = force / (A * total);
  const int n = grid.n;
  for (int j = 0; j < n; ++j) {
    int begin = -1;
    for (int i = 0; i <= n; ++i) {
      bool on = false;
      if (i < n) {
        const size_t idx = static_cast<size_t>(j) * n + i;
        const double d = c - gap[idx];
        if (d > 0.0 && cov[idx] > 0.0) {
          out->pressure[idx] = static_cast<float>(scale * cov[idx] * d);
          on = true;
          ++out->active_cells;
        }
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
  out->approach_m = c;
  return true;
}

void UniformSlipShear(const TaxelGrid& grid, double fn, double fx, double fy,
                      TractionField* field) {
  const size_t N = grid.Size();
  field->shear_x.assign(N, 0.0f);
  field->shear_y.assign(N, 0.0f);
  if (!(fn > 0.0)) return;
  const float rx = static_cast<float>(fx / fn), ry = static_cast<float>(fy / fn);
  for (size_t i = 0; i < N; ++i) {
    field->shear_x[i] = rx * field->pressure[i];
    field->shear_y[i] = ry * field->pressure[i];
  }
}

}  // namespace mjtouch
