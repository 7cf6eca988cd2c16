#include "contact/pressure.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "contact/traction_cells.h"

namespace mjtouch {

const char* PressureModelName(PressureModel m) {
  switch (m) {
    case PressureModel::kContacts: return "contacts";
    case PressureModel::kWinkler: return "winkler";
    default: return "elastic";
  }
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
  if (TractionSized(grid, *f) && f->support_in_runs) {
    const unsigned held = HeldArrays(*f);  // (the lazy arrays are zero)
    for (size_t r = 0; r < f->runs.row.size(); ++r) {
      const size_t row = static_cast<size_t>(f->runs.row[r]) * grid.n;
      ZeroCells(f, row + f->runs.begin[r], row + f->runs.end[r], held);
    }
  } else {
    for (auto* v : {&f->pressure_pa, &f->shear_x_pa, &f->shear_y_pa}) {
      if (v->size() != N)
        v->assign(N, 0.0);
      else
        ForBox(grid, f->box, [&](size_t k) { (*v)[k] = 0.0; });
    }
    for (auto* v : {&f->pressure, &f->shear_x, &f->shear_y}) {
      if (v->size() != N)
        v->assign(N, 0.0f);
      else
        ForBox(grid, f->box, [&](size_t k) { (*v)[k] = 0.0f; });
    }
  }
  f->support_in_runs = false;
  f->lazy_pressure_pa = f->lazy_shear = false;
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
  out->runs.Clear();
  out->active_cells = 0;
  // Row by row: the float copies (vectorised), then the runs of active cells
  // while the row is in cache.
  for (int j = b.j0; j < b.j0 + b.ny; ++j) {
    const size_t row = static_cast<size_t>(j) * grid.n;
    const double* p = out->pressure_pa.data() + row;
    const double* sx = out->shear_x_pa.data() + row;
    const double* sy = out->shear_y_pa.data() + row;
    float* fp = out->pressure.data() + row;
    float* fx = out->shear_x.data() + row;
    float* fy = out->shear_y.data() + row;
    const int i0 = b.i0, i1 = b.i0 + b.nx;
    for (int i = i0; i < i1; ++i) fp[i] = static_cast<float>(p[i]);
    if (shear) {
      for (int i = i0; i < i1; ++i) fx[i] = static_cast<float>(sx[i]);
      for (int i = i0; i < i1; ++i) fy[i] = static_cast<float>(sy[i]);
    } else {
      std::fill(fx + i0, fx + i1, 0.0f);
      std::fill(fy + i0, fy + i1, 0.0f);
    }
    auto on = [&](int i) { return p[i] != 0.0 || (shear && (sx[i] != 0.0 || sy[i] != 0.0)); };
    ForEachRun(i0, i1, on, [&](int begin, int end) {
      out->runs.Add(j, begin, end);
      out->active_cells += end - begin;
    });
  }
}

namespace {

// One run of loaded cells: shear = ratio x pressure, and the float copies
// (the arrays do not overlap: vectorised without alias checks).
void SlipRun(const double* __restrict p, double rx, double ry, int len, double* __restrict sx,
             double* __restrict sy, float* __restrict fp, float* __restrict fx,
             float* __restrict fy) {
  for (int k = 0; k < len; ++k) {
    const double qx = rx * p[k], qy = ry * p[k];
    sx[k] = qx;
    sy[k] = qy;
    fp[k] = static_cast<float>(p[k]);
    fx[k] = static_cast<float>(qx);
    fy[k] = static_cast<float>(qy);
  }
}

}  // namespace

void FinishUniformSlipTraction(const TaxelGrid& grid, double fn, double fx, double fy,
                               TractionField* out) {
  SetUniformSlip(fn, fx, fy, out);
  const double rx = out->slip_x, ry = out->slip_y;
  const CellBox& b = out->box;
  out->runs.Clear();
  out->active_cells = 0;
  // Nonzero pressure only in the box (the pressure models write no -0), so
  // after this every field is zero outside the runs.
  out->support_in_runs = true;
  // Only the loaded cells are written: the rest of every field is zero
  // already (ClearTraction), as UniformSlipShear and FinishTraction leave it.
  for (int j = b.j0; j < b.j0 + b.ny; ++j) {
    const size_t row = static_cast<size_t>(j) * grid.n;
    const double* p = out->pressure_pa.data() + row;
    ForEachRun(
        b.i0, b.i0 + b.nx, [&](int i) { return p[i] != 0.0; },
        [&](int begin, int end) {
          out->runs.Add(j, begin, end);
          out->active_cells += end - begin;
          SlipRun(p + begin, rx, ry, end - begin, out->shear_x_pa.data() + row + begin,
                  out->shear_y_pa.data() + row + begin, out->pressure.data() + row + begin,
                  out->shear_x.data() + row + begin, out->shear_y.data() + row + begin);
        });
  }
}

bool SplatContacts(const TaxelGrid& grid, const std::vector<ContactPoint>& contacts,
                   TractionField* out) {
  ClearTraction(grid, out);
  const double inv_area = 1.0 / grid.Area();
  double total = 0.0;
  const int n = grid.n;
  CellBounds loaded;
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
    loaded.AddRow(i0, i0 + 1, j0);
    loaded.AddRow(i0, i0 + 1, j0 + 1);
    total += c.force_n[2];
  }
  if (!loaded.empty()) out->box = loaded.Box();
  return total > 0.0;
}

bool WinklerPressureReference(const TaxelGrid& grid, const std::vector<double>& gap,
                              const std::vector<double>& cov, const CellBox& box, double k,
                              double force, double guess, TractionField* out) {
  ClearTraction(grid, out);
  const double A = grid.Area();
  // Solve f(c) = sum cov_i max(c - g_i, 0) - force / (k A) = 0 over the
  // candidates (packed once: every pass below reads them contiguously). f is
  // convex, piecewise linear and increasing, so Newton from the right of the
  // root converges monotonically in finitely many steps.
  const double target = force / (k * A);
  std::vector<double>& cg = out->scratch_gap;
  std::vector<double>& cc = out->scratch_cov;
  std::vector<size_t> ci;
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
      if (d > 0.0) {
        f += cc[i] * d;
        s += cc[i];
      }
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
  // The sums in four lanes, lane k over the cells of columns i = k mod 4 in
  // box order (WinklerLaneSum), as the fast path vectorises them.
  const int n = grid.n;
  for (int pass = 0; pass < 4; ++pass) {
    double lane_cov[4] = {0, 0, 0, 0}, lane_cov_g[4] = {0, 0, 0, 0};
    for (size_t i = 0; i < M; ++i) {
      if (c - cg[i] > 0.0) {
        const size_t l = (ci[i] % n) & 3;
        lane_cov[l] += cc[i];
        lane_cov_g[l] += cc[i] * cg[i];
      }
    }
    const double sum_cov = WinklerLaneSum(lane_cov), sum_cov_g = WinklerLaneSum(lane_cov_g);
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
  // NormalizeLoad with the load summed in the lanes above.
  double lane_load[4] = {0, 0, 0, 0};
  ForBox(grid, box, [&](size_t k) { lane_load[(k % n) & 3] += out->pressure_pa[k]; });
  const double total = WinklerLaneSum(lane_load);
  if (!(total > 0.0)) {
    ForBox(grid, box, [&](size_t k) { out->pressure_pa[k] = 0.0; });
    return false;
  }
  const double scale = force / (A * total);
  ForBox(grid, box, [&](size_t k) { out->pressure_pa[k] *= scale; });
  return true;
}

void UniformSlipShear(const TaxelGrid& grid, double fn, double fx, double fy,
                      TractionField* field) {
  SetUniformSlip(fn, fx, fy, field);
  const double rx = field->slip_x, ry = field->slip_y;
  // Unloaded cells keep the zero ClearTraction left (not rx * 0, which is
  // -0 for rx < 0), so that the shear is zero wherever the pressure is.
  ForBox(grid, field->box, [&](size_t i) {
    const double p = field->pressure_pa[i];
    if (p == 0.0) return;
    field->shear_x_pa[i] = rx * p;
    field->shear_y_pa[i] = ry * p;
  });
}

}  // namespace mjtouch
