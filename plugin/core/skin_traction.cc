// Stages 1-2 of the pipeline for one step: render the gap (surface.h) and
// turn it and MuJoCo's contact force into surface tractions (pressure.h,
// contact_solver.h) with the model chosen by the `pressure` attribute.
// Everything depends on the step's inputs and `state` only (warm starts
// come from plugin_state), so copies and resets reproduce runs bit for bit.
#include <algorithm>
#include <cmath>
#include <limits>

#include "skin.h"

namespace mjtouch {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kElasticMaxIterations = 500;

// Smallest gap over the covered cells of the box (+inf if none).
double MinGap(const TaxelGrid& grid, const CellBox& box, const std::vector<double>& gap,
              const std::vector<double>& cov) {
  double gmin = kInf;
  for (int j = box.j0; j < box.j0 + box.ny; ++j)
    for (int i = box.i0; i < box.i0 + box.nx; ++i) {
      const size_t k = static_cast<size_t>(j) * grid.n + i;
      if (cov[k] > 0.0) gmin = std::min(gmin, gap[k]);
    }
  return gmin;
}

}  // namespace

bool ComputeTraction(const SkinModel& model, const StepInput& in, double* state,
                     Workspace* ws) {
  const SkinConfig& cfg = model.config();
  const TaxelGrid& grid = cfg.grid;
  TractionField& tf = ws->traction;
  const bool warm = state[kStContactValid] > 0.0;
  const double depth_prev = state[kStContactDepth];
  const double level_prev = state[kStContactLevel];
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
    CellBox box;
    double cull = RenderGap(grid, model.skin_z(), in.pad_pose, in.surfaces, cull_rel, &ws->gap,
                            &ws->coverage, true, &model.skin_blocks(), &box);
    for (int pass = 0; pass < 2 && !touching; ++pass) {
      if (pass == 1) {
        cull = RenderGap(grid, model.skin_z(), in.pad_pose, in.surfaces, kInf, &ws->gap,
                         &ws->coverage, true, &model.skin_blocks(), &box);
      }
      const double gmin = MinGap(grid, box, ws->gap, ws->coverage);
      if (!std::isfinite(gmin)) break;
      double approach = 0.0, level = 0.0;
      if (cfg.pressure_model == PressureModel::kWinkler) {
        const double guess = warm ? gmin + depth_prev : std::nan("");
        touching = WinklerPressure(grid, ws->gap, ws->coverage, box, cfg.stiffness_pa_per_m,
                                   in.normal_force_n, guess, &tf);
        approach = tf.approach_m;
      } else {
        const ElasticContact& ec = *model.elastic();
        // Cells without coverage never touch.
        for (int j = box.j0; j < box.j0 + box.ny; ++j)
          for (int i = box.i0; i < box.i0 + box.nx; ++i) {
            const size_t k = static_cast<size_t>(j) * grid.n + i;
            if (!(ws->coverage[k] > 0.0)) ws->gap[k] = kInf;
          }
        // Initial guess from the last step's contact level L (largest gap in
        // contact above the smallest): p ~ sqrt(L - (g - gmin)), which is
        // Hertz's distribution for a paraboloid and close for any smooth
        // shape. It depends on plugin_state only, never on scratch memory.
        ws->pressure_guess.assign(grid.Size(), 0.0);
        if (warm && level_prev > 0.0) {
          for (size_t k = 0; k < grid.Size(); ++k) {
            const double d = level_prev - (ws->gap[k] - gmin);
            if (d > 0.0) ws->pressure_guess[k] = std::sqrt(d);
          }
        }
        ElasticSolveStats st;
        touching = ec.Solve(ws->gap, box, in.normal_force_n, cfg.tolerance,
                            kElasticMaxIterations, &ws->pressure_guess, &ws->elastic, &st);
        if (touching) {
          tf.pressure_pa.swap(ws->pressure_guess);
          tf.box = box;
          touching = NormalizeLoad(grid, in.normal_force_n, &tf);
        }
        approach = st.approach_m;
        level = st.max_contact_gap_m - gmin;
      }
      if (touching && approach >= cull && pass == 0) {
        touching = false;  // render all and solve again
        ClearTraction(grid, &tf);
        continue;
      }
      if (touching) {
        state[kStContactDepth] = approach - gmin;
        state[kStContactLevel] = level;
      }
    }
    if (touching && cfg.shear)
      UniformSlipShear(grid, in.normal_force_n, in.shear_x_n, in.shear_y_n, &tf);
  }
  if (touching) {
    FinishTraction(grid, cfg.shear, &tf);
    state[kStContactValid] = 1.0;
  }
  return touching;
}

}  // namespace mjtouch
