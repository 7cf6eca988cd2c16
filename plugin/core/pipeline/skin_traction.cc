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

// CPU time of the calling thread (benchmarks: Workspace::render_time_s).
double ThreadCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
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

}  // namespace

bool ComputeTraction(const SkinModel& model, const StepInput& in, double* state,
                     Workspace* ws) {
  const SkinConfig& cfg = model.config();
  const TaxelGrid& grid = cfg.grid;
  TractionField& tf = ws->traction;
  const bool warm = state[kStContactValid] > 0.0;
  const double depth_prev = state[kStContactDepth];
  state[kStContactValid] = 0.0;
  if (!(in.in_contact && in.normal_force_n > 0.0)) return false;

  bool touching = false;
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
                                     fast);
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
        const StateLayout& lay = model.state_layout();
        const double* last = state + lay.last_pressure;
        const double* prev = state + lay.prev_pressure;
        const bool extrapolate =
            warm && lay.prev_pressure_size > 0 && prev[lay.last_pressure_size] > 0.0;
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
        // The solve box: cells that can touch if the approach is at most 1.2
        // x the last step's depth above gmin (+ 10 um). A cell whose gap
        // exceeds the approach by more than the largest bulge of the skin
        // never touches, so if the solved approach stays below that level
        // the box held every contact; else solve again on every rendered
        // cell.
        const double lift = ec.max_lift_m_per_pa() * in.normal_force_n / grid.Area();
        const double level = gmin + 1.2 * depth_prev + 10e-6;
        CellBox solve_box = box;
        if (warm) {
          int i0 = grid.n, i1 = -1, j0 = grid.n, j1 = -1;
          for (int j = box.j0; j < box.j0 + box.ny; ++j)
            for (int i = box.i0; i < box.i0 + box.nx; ++i)
              if (ws->gap[static_cast<size_t>(j) * grid.n + i] <= level + lift) {
                i0 = std::min(i0, i);
                i1 = std::max(i1, i);
                j0 = std::min(j0, j);
                j1 = std::max(j1, j);
              }
          if (i1 >= 0) solve_box = CellBox{i0, j0, i1 - i0 + 1, j1 - j0 + 1};
        }
        ElasticSolveStats st;
        for (int attempt = 0; attempt < 2; ++attempt) {
          if (attempt == 1) {  // the tight box was too small: every rendered cell
            if (!warm) break;
            solve_box = box;
            warm_guess();
          }
          touching = ec.Solve(ws->gap, solve_box, in.normal_force_n, cfg.tolerance,
                              kElasticMaxIterations, &ws->pressure_guess, &ws->elastic, &st,
                              cfg.elastic_method);
          if (!touching || !warm || st.approach_m <= level) break;
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
    if (touching && cfg.shear)
      UniformSlipShear(grid, in.normal_force_n, in.shear_x_n, in.shear_y_n, &tf);
  }
  if (touching) {
    FinishTraction(grid, cfg.shear, &tf);
    state[kStContactValid] = 1.0;
    if (cfg.pressure_model == PressureModel::kElastic) {
      const StateLayout& lay = model.state_layout();
      if (lay.prev_pressure_size > 0) {  // p(n-2) <- p(n-1), valid if that step touched
        std::copy(state + lay.last_pressure, state + lay.last_pressure + lay.last_pressure_size,
                  state + lay.prev_pressure);
        state[lay.prev_pressure + lay.last_pressure_size] = warm ? 1.0 : 0.0;
      }
      std::copy(tf.pressure_pa.begin(), tf.pressure_pa.end(), state + lay.last_pressure);
    }
  }
  return touching;
}

}  // namespace mjtouch
