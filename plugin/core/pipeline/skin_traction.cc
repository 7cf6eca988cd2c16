// Stages 1-2 of the pipeline for one step: render the gap (surface.h) and
// turn it and MuJoCo's contact force into surface tractions (pressure.h,
// contact_solver.h) with the model chosen by the `pressure` attribute.
// Everything depends on the step's inputs and `state` only (warm starts
// come from plugin_state), so copies and resets reproduce runs bit for bit.
#include <algorithm>
#include <cmath>
#include <limits>

#include <time.h>

#include "pipeline/skin.h"

namespace mjtouch {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kElasticMaxIterations = 500;
// Cells the elastic solve box extends beyond the last step's contact (a
// sliding contact moves well under a cell per step).
constexpr int kBoxMarginCells = 3;
// Solves on a grown box before the whole rendered box.
constexpr int kBoxAttempts = 3;

// CPU time of the calling thread (benchmarks: Workspace::render_time_s).
double ThreadCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

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

// True if no rendered cell (box) outside `inner` can touch under the
// pressure solved on `inner` (zero elsewhere): g0 + K p >= approach there.
// Cells with g0 > approach + lift (lift: a bound on the skin's upward bulge)
// pass without the operator; the rest get u from one application on their
// bounding box. If some cell fails, *grown is the bounding box of inner and
// the failing cells, kBoxMarginCells wider (within box).
bool BoxHoldsContact(const TaxelGrid& grid, const SurfaceCompliance& K,
                     const std::vector<double>& gap, const CellBox& box, const CellBox& inner,
                     const std::vector<double>& pressure, double approach_m, double lift_m,
                     ApplyPrecision precision, ElasticWork* w, CellBox* grown) {
  auto outside = [&](int i, int j) {
    return i < inner.i0 || i >= inner.i0 + inner.nx || j < inner.j0 || j >= inner.j0 + inner.ny;
  };
  int i0 = inner.i0, i1 = inner.i0 + inner.nx - 1, j0 = inner.j0, j1 = inner.j0 + inner.ny - 1;
  bool any = false;
  for (int j = box.j0; j < box.j0 + box.ny; ++j)
    for (int i = box.i0; i < box.i0 + box.nx; ++i)
      if (outside(i, j) && gap[static_cast<size_t>(j) * grid.n + i] <= approach_m + lift_m) {
        any = true;
        i0 = std::min(i0, i);
        i1 = std::max(i1, i);
        j0 = std::min(j0, j);
        j1 = std::max(j1, j);
      }
  if (!any) return true;
  const int cx = i1 - i0 + 1, cy = j1 - j0 + 1;
  w->check_p.assign(static_cast<size_t>(cx) * cy, 0.0);
  w->check_u.resize(w->check_p.size());
  for (int j = inner.j0; j < inner.j0 + inner.ny; ++j)
    for (int i = inner.i0; i < inner.i0 + inner.nx; ++i)
      w->check_p[static_cast<size_t>(j - j0) * cx + (i - i0)] =
          pressure[static_cast<size_t>(j) * grid.n + i];
  const auto spec = K.SpectrumFor(cx, cy);
  K.Apply(*spec, w->check_p.data(), cx, cy, w->check_u.data(), &w->fft, precision);
  int f0 = inner.i0, f1 = inner.i0 + inner.nx - 1, g0 = inner.j0, g1 = inner.j0 + inner.ny - 1;
  bool ok = true;
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const double g = gap[static_cast<size_t>(j) * grid.n + i];
      if (outside(i, j) && g <= approach_m + lift_m &&
          !(g + w->check_u[static_cast<size_t>(j - j0) * cx + (i - i0)] >= approach_m)) {
        ok = false;
        f0 = std::min(f0, i);
        f1 = std::max(f1, i);
        g0 = std::min(g0, j);
        g1 = std::max(g1, j);
      }
    }
  if (!ok) *grown = GrowBox(box, f0, f1, g0, g1);
  return ok;
}

}  // namespace

bool ComputeTraction(const SkinModel& model, const StepInput& in, double* state,
                     Workspace* ws, bool new_time) {
  const SkinConfig& cfg = model.config();
  const TaxelGrid& grid = cfg.grid;
  TractionField& tf = ws->traction;
  // `elastic`: the last step's contact from the pressure history, so a
  // repeated evaluation at the same time starts where the first one did.
  const StateLayout& lay = model.state_layout();
  const size_t ncell = grid.Size();
  double* cur = nullptr;
  const double *last = nullptr, *prev = nullptr;
  if (lay.history_block > 0) {
    if (new_time)
      state[lay.history_head] = (static_cast<int>(state[lay.history_head]) + 1) % kHistoryBlocks;
    cur = lay.history_at(state, 0);
    last = lay.history_at(state, 1);
    prev = lay.history_at(state, 2);
    cur[ncell + kHsValid] = 0.0;
  }
  const bool warm = last ? last[ncell + kHsValid] > 0.0 : state[kStContactValid] > 0.0;
  const double depth_prev = last ? last[ncell + kHsDepth] : state[kStContactDepth];
  state[kStContactValid] = 0.0;
  if (!(in.in_contact && in.normal_force_n > 0.0)) return false;

  bool touching = false;
  bool finished = false;  // FinishTraction done
  if (cfg.pressure_model == PressureModel::kContacts) {
    touching = SplatContacts(grid, in.contacts, &tf);
    state[kStContactDepth] = 0.0;
  } else if (!in.surfaces.empty()) {
    ClearTraction(grid, &tf);
    // Warm start: the last step's indentation depth (approach minus smallest
    // gap) bounds which cells can touch; cells provably above 1.5x that
    // depth are not rendered. A cell whose gap exceeds the approach cannot
    // touch in either model (the skin's displacement only adds to the gap),
    // so if the solved approach reaches the cull level, render everything and
    // solve again: the result is exact either way.
    const double cull_rel = warm ? 1.5 * depth_prev + 20e-6 : kInf;
    const bool fast = !ws->reference_paths;
    CellBox box;
    auto render = [&](double cull_above_m) {
      const double t0 = ws->render_time_s ? ThreadCpuSeconds() : 0.0;
      const double level = RenderGap(grid, model.skin_z(), in.pad_pose, in.surfaces, cull_above_m,
                                     &ws->gap, &ws->coverage, true, &model.skin_blocks(), &box,
                                     fast, fast ? &ws->gap_written : nullptr);
      if (!fast) ws->gap_written = CellBox::All(grid);  // the reference cleared it all
      if (ws->render_time_s) *ws->render_time_s += ThreadCpuSeconds() - t0;
      return level;
    };
    double cull = render(cull_rel);
    for (int pass = 0; pass < 2 && !touching; ++pass) {
      if (pass == 1) cull = render(kInf);
      const double gmin = MinGap(grid, box, ws->gap, ws->coverage);
      if (!std::isfinite(gmin)) break;
      double approach = 0.0;
      if (cfg.pressure_model == PressureModel::kWinkler) {
        const double guess = warm ? gmin + depth_prev : std::nan("");
        touching = (fast ? WinklerPressure : WinklerPressureReference)(
            grid, ws->gap, ws->coverage, box, cfg.stiffness_pa_per_m, in.normal_force_n, guess,
            &tf);
        approach = tf.approach_m;
      } else {
        const ElasticContact& ec = *model.elastic();
        // Cells without coverage never touch.
        for (int j = box.j0; j < box.j0 + box.ny; ++j)
          for (int i = box.i0; i < box.i0 + box.nx; ++i) {
            const size_t k = static_cast<size_t>(j) * grid.n + i;
            if (!(ws->coverage[k] > 0.0)) ws->gap[k] = kInf;
          }
        // Warm start: the last step's pressure field (plugin_state), so a
        // sliding contact needs a few iterations; cold: uniform. With
        // contact_solver = pcg, extrapolated 2 p(n-1) - p(n-2) when both
        // steps touched (prototype on slide_grating, P&K: 16.6 -> 9.7
        // iterations at the same error).
        const bool extrapolate = warm &&
                                 cfg.elastic_method == ElasticMethod::kPreconditioned &&
                                 prev[ncell + kHsValid] > 0.0;
        auto warm_guess = [&]() {
          ws->pressure_guess.assign(grid.Size(), 0.0);
          if (!warm) return;
          if (extrapolate) {
            for (size_t k = 0; k < grid.Size(); ++k)
              ws->pressure_guess[k] = std::max(0.0, 2.0 * last[k] - prev[k]);
          } else {
            std::copy(last, last + grid.Size(), ws->pressure_guess.begin());
          }
        };
        warm_guess();
        // The solve box: the last step's contact, kBoxMarginCells wider.
        // The gap alone bounds it poorly: an elastic contact is ~1/sqrt(2)
        // as wide as the region where the surfaces interpenetrate, and a
        // layered skin bulges beside a load. So the box is checked after the
        // solve (BoxHoldsContact: no rendered cell outside it may touch) and
        // grown around the cells that would; after kBoxAttempts, every
        // rendered cell. The result solves the contact problem on the
        // rendered cells either way.
        CellBox solve_box = box;
        if (warm) {
          int i0 = grid.n, i1 = -1, j0 = grid.n, j1 = -1;
          for (int j = box.j0; j < box.j0 + box.ny; ++j)
            for (int i = box.i0; i < box.i0 + box.nx; ++i)
              if (last[static_cast<size_t>(j) * grid.n + i] > 0.0) {
                i0 = std::min(i0, i);
                i1 = std::max(i1, i);
                j0 = std::min(j0, j);
                j1 = std::max(j1, j);
              }
          if (i1 >= 0) solve_box = GrowBox(box, i0, i1, j0, j1);
        }
        // Upward bulge bound: max_lift times the whole load on one cell.
        const double lift = ec.max_lift_m_per_pa() * in.normal_force_n / grid.Area();
        ElasticSolveStats st;
        for (int attempt = 0;; ++attempt) {
          touching = ec.Solve(ws->gap, solve_box, in.normal_force_n, cfg.tolerance,
                              kElasticMaxIterations, &ws->pressure_guess, &ws->elastic, &st,
                              cfg.elastic_method, cfg.elastic_precision);
          const bool whole = solve_box.i0 == box.i0 && solve_box.j0 == box.j0 &&
                             solve_box.nx == box.nx && solve_box.ny == box.ny;
          if (whole) break;
          CellBox grown = box;
          if (touching && BoxHoldsContact(grid, ec.compliance(), ws->gap, box, solve_box,
                                          ws->pressure_guess, st.approach_m, lift,
                                          cfg.elastic_precision, &ws->elastic, &grown))
            break;
          // the solution on the smaller box is a good start on the grown one
          solve_box = touching && attempt + 1 < kBoxAttempts ? grown : box;
        }
        if (touching) {
          tf.pressure_pa.swap(ws->pressure_guess);
          tf.box = solve_box;
          touching = NormalizeLoad(grid, in.normal_force_n, &tf);
        }
        ws->elastic_stats = st;
        approach = st.approach_m;
      }
      if (touching && approach >= cull && pass == 0) {
        touching = false;  // render all and solve again
        ClearTraction(grid, &tf);
        continue;
      }
      if (touching) {
        state[kStContactDepth] = approach - gmin;
      }
    }
    if (touching && cfg.shear) {
      if (ws->reference_paths) {
        UniformSlipShear(grid, in.normal_force_n, in.shear_x_n, in.shear_y_n, &tf);
      } else {  // the shear and FinishTraction in one pass
        FinishUniformSlipTraction(grid, in.normal_force_n, in.shear_x_n, in.shear_y_n, &tf);
        finished = true;
      }
    }
  }
  if (touching) {
    if (!finished) FinishTraction(grid, cfg.shear, &tf);
    state[kStContactValid] = 1.0;
    if (cur) {
      std::copy(tf.pressure_pa.begin(), tf.pressure_pa.end(), cur);
      cur[ncell + kHsValid] = 1.0;
      cur[ncell + kHsDepth] = state[kStContactDepth];
    }
  }
  return touching;
}

}  // namespace mjtouch
