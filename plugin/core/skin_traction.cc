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

double MinGap(const std::vector<double>& gap, const std::vector<double>& cov) {
  double gmin = kInf;
  for (size_t i = 0; i < gap.size(); ++i)
    if (cov[i] > 0.0) gmin = std::min(gmin, gap[i]);
  return gmin;
}

// Cells that can touch get a finite gap; the rest +inf. Returns their
// bounding box (empty if none).
CellBox CandidateBox(const TaxelGrid& grid, std::vector<double>* gap,
                     const std::vector<double>& cov) {
  int i0 = grid.n, i1 = -1, j0 = grid.n, j1 = -1;
  for (int j = 0; j < grid.n; ++j) {
    for (int i = 0; i < grid.n; ++i) {
      const size_t k = static_cast<size_t>(j) * grid.n + i;
      if (!(cov[k] > 0.0) || !std::isfinite((*gap)[k])) {
        (*gap)[k] = kInf;
        continue;
      }
      i0 = std::min(i0, i);
      i1 = std::max(i1, i);
      j0 = std::min(j0, j);
      j1 = std::max(j1, j);
    }
  }
  if (i1 < 0) return CellBox{0, 0, 0, 0};
  return CellBox{i0, j0, i1 - i0 + 1, j1 - j0 + 1};
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
    if (!cfg.shear) {
      tf.shear_x_pa.clear();
      tf.shear_y_pa.clear();
    }
    state[kStContactDepth] = 0.0;
  } else if (!in.surfaces.empty()) {
    // Warm start: the last step's indentation depth (approach minus smallest
    // gap) bounds which cells can touch; cells provably above 1.5x that
    // depth are not rendered. A cell whose gap exceeds the approach cannot
    // touch in either model (the skin's displacement only adds to the gap),
    // so if the solved approach reaches the cull level, render everything and
    // solve again: the result is exact either way.
    const double cull_rel = warm ? 1.5 * depth_prev + 20e-6 : kInf;
    double cull = RenderGap(grid, model.skin_z(), in.pad_pose, in.surfaces, cull_rel, &ws->gap,
                            &ws->coverage);
    for (int pass = 0; pass < 2 && !touching; ++pass) {
      if (pass == 1) {
        cull = RenderGap(grid, model.skin_z(), in.pad_pose, in.surfaces, kInf, &ws->gap,
                         &ws->coverage);
      }
      const double gmin = MinGap(ws->gap, ws->coverage);
      if (!std::isfinite(gmin)) break;
      double approach = 0.0, level = 0.0;
      if (cfg.pressure_model == PressureModel::kWinkler) {
        const double guess = warm ? gmin + depth_prev : std::nan("");
        touching = WinklerPressure(grid, ws->gap, ws->coverage, cfg.stiffness_pa_per_m,
                                   in.normal_force_n, guess, &tf);
        approach = tf.approach_m;
      } else {
        const ElasticContact& ec = *model.elastic();
        const CellBox box = CandidateBox(grid, &ws->gap, ws->coverage);
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
          touching = NormalizeLoad(grid, in.normal_force_n, &tf);
        }
        approach = st.approach_m;
        level = st.max_contact_gap_m - gmin;
      }
      if (touching && approach >= cull && pass == 0) {
        touching = false;  // render all and solve again
        continue;
      }
      if (touching) {
        state[kStContactDepth] = approach - gmin;
        state[kStContactLevel] = level;
      }
    }
    if (touching) {
      if (cfg.shear) {
        UniformSlipShear(grid, in.normal_force_n, in.shear_x_n, in.shear_y_n, &tf);
      } else {
        tf.shear_x_pa.clear();
        tf.shear_y_pa.clear();
      }
    }
  }
  if (touching) {
    FinishTraction(grid, &tf);
    state[kStContactValid] = 1.0;
  }
  return touching;
}

}  // namespace mjtouch
