#include "pressure.h"

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

void SetPressure(const TaxelGrid& grid, const std::vector<double>& p, TractionField* out) {
  const size_t N = grid.Size();
  out->pressure_pa.assign(N, 0.0);
  for (size_t i = 0; i < N; ++i) out->pressure_pa[i] = p[i] > 0.0 ? p[i] : 0.0;
}

bool NormalizeLoad(const TaxelGrid& grid, double force, TractionField* out) {
  double total = 0.0;
  for (double v : out->pressure_pa) total += v;
  if (!(total > 0.0) || !(force > 0.0)) {
    std::fill(out->pressure_pa.begin(), out->pressure_pa.end(), 0.0);
    return false;
  }
  const double scale = force / (grid.Area() * total);
  for (double& v : out->pressure_pa) v *= scale;
  return true;
}

void FinishTraction(const TaxelGrid& grid, TractionField* out) {
  const size_t N = grid.Size();
  const bool shear = out->shear_x_pa.size() == N && out->shear_y_pa.size() == N;
  out->pressure.resize(N);
  for (size_t i = 0; i < N; ++i) out->pressure[i] = static_cast<float>(out->pressure_pa[i]);
  out->shear_x.assign(N, 0.0f);
  out->shear_y.assign(N, 0.0f);
  if (shear) {
    for (size_t i = 0; i < N; ++i) {
      out->shear_x[i] = static_cast<float>(out->shear_x_pa[i]);
      out->shear_y[i] = static_cast<float>(out->shear_y_pa[i]);
    }
  }
  out->runs.Clear();
  out->active_cells = 0;
  const int n = grid.n;
  for (int j = 0; j < n; ++j) {
    int begin = -1;
    for (int i = 0; i <= n; ++i) {
      bool on = false;
      if (i < n) {
        const size_t idx = static_cast<size_t>(j) * n + i;
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
  const size_t N = grid.Size();
  out->pressure_pa.assign(N, 0.0);
  out->shear_x_pa.assign(N, 0.0);
  out->shear_y_pa.assign(N, 0.0);
  out->approach_m = 0.0;
  const double inv_area = 1.0 / grid.Area();
  double total = 0.0;
  const int n = grid.n;
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
    total += c.force_n[2];
  }
  return total > 0.0;
}

bool WinklerPressure(const TaxelGrid& grid, const std::vector<double>& gap,
                     const std::vector<double>& cov, double k, double force,
                     double guess, TractionField* out) {
  const size_t N = grid.Size();
  out->pressure_pa.assign(N, 0.0);
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
  out->pressure_pa.assign(N, 0.0);
  for (size_t i = 0; i < N; ++i) {
    const double d = c - gap[i];
    if (d > 0.0 && cov[i] > 0.0) out->pressure_pa[i] = cov[i] * d;
  }
  out->approach_m = c;
  return NormalizeLoad(grid, force, out);
}

void UniformSlipShear(const TaxelGrid& grid, double fn, double fx, double fy,
                      TractionField* field) {
  const size_t N = grid.Size();
  field->shear_x_pa.assign(N, 0.0);
  field->shear_y_pa.assign(N, 0.0);
  if (!(fn > 0.0)) return;
  const double rx = fx / fn, ry = fy / fn;
  for (size_t i = 0; i < N; ++i) {
    field->shear_x_pa[i] = rx * field->pressure_pa[i];
    field->shear_y_pa[i] = ry * field->pressure_pa[i];
  }
}

}  // namespace mjtouch
