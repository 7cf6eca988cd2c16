// Stages 1-2 of the pipeline for one step: render the gap (surface.h) and
// turn it and MuJoCo's contact force into surface tractions (pressure.h,
// contact_solver.h) with the model chosen by the `pressure` attribute.
// Everything depends on the step's inputs and `state` only (warm starts
// come from plugin_state), so copies and resets reproduce runs bit for bit.
#include <algorithm>
#include <utility>
#include <cmath>
#include <limits>

#include <time.h>

#include "pipeline/skin.h"
#include "pipeline/warm_start.h"

namespace mjtouch {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kElasticMaxIterations = 500;
// Winkler + shear (fast paths): the cull level above the smallest gap, in
// last step's indentation depths plus a margin (the other models: 1.5 and
// 20 um). Any level gives the same result (a level the approach reaches
// renders again without culling); a tight one renders and scans fewer cells.
constexpr double kWinklerCullDepths = 1.1, kWinklerCullM = 3e-6;

// The `elastic` solves' settings, threads included.
ElasticSolveOptions ElasticOptions(const SkinConfig& cfg) {
  ElasticSolveOptions o;
  o.tolerance = cfg.tolerance;
  o.max_iterations = kElasticMaxIterations;
  o.method = cfg.elastic_method;
  o.precision = cfg.elastic_precision;
  o.threads = cfg.threads;
  return o;
}

// CPU time of the calling thread (benchmarks: Workspace::render_time_s).
double ThreadCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
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
  const bool history = lay.history_block > 0;
  // this time, the last step, the one before: the taxel grid's and the shifted grid's
  HistoryBlock taxel[3]{}, shifted[3]{};
  const bool shifted_history = lay.shifted_block > 0;
  if (history) {
    if (new_time)
      state[lay.history_head] = (static_cast<int>(state[lay.history_head]) + 1) % kHistoryBlocks;
    for (int back = 0; back < 3; ++back) taxel[back] = lay.history_at(state, back);
    taxel[0].slots[kHsValid] = 0.0;
    if (shifted_history) {
      for (int back = 0; back < 3; ++back) shifted[back] = lay.shifted_history_at(state, back);
      shifted[0].slots[kHsValid] = 0.0;
    }
  }
  const bool warm = history ? HasWarmStart(taxel) : state[kStContactValid] > 0.0;
  const double depth_prev = history ? taxel[1].slots[kHsDepth] : state[kStContactDepth];
  state[kStContactValid] = 0.0;
  if (!(in.in_contact && in.normal_force_n > 0.0)) return false;

  bool touching = false;
  bool finished = false;  // FinishTraction done
  if (cfg.pressure_model == PressureModel::kContacts) {
    touching = SplatContacts(grid, in.contacts, &tf);
    state[kStContactDepth] = 0.0;
  } else if (!in.surfaces.empty()) {
    // Winkler with shear (fast paths): solved first, then the field written
    // over the last one (WriteWinklerSlipTraction), which clears only what
    // the new contact does not cover.
    const bool winkler_slip = !ws->reference_paths &&
                              cfg.pressure_model == PressureModel::kWinkler && cfg.shear;
    if (!winkler_slip) ClearTraction(grid, &tf);
    // Warm start: the last step's indentation depth (approach minus smallest
    // gap) bounds which cells can touch; cells provably above 1.5x that
    // depth are not rendered. A cell whose gap exceeds the approach cannot
    // touch in either model (the skin's displacement only adds to the gap),
    // so if the solved approach reaches the cull level, render everything and
    // solve again: the result is exact either way.
    const double cull_rel = !warm ? kInf
                            : winkler_slip ? kWinklerCullDepths * depth_prev + kWinklerCullM
                                           : CullLevel(depth_prev);
    const bool fast = !ws->reference_paths;
    CellBox box;
    auto render = [&](double cull_above_m) {
      const double t0 = ws->render_time_s ? ThreadCpuSeconds() : 0.0;
      const double level = RenderGap(grid, model.skin_z(), in.pad_pose, in.surfaces, cull_above_m,
                                     &ws->gap, &ws->coverage, true, &model.skin_blocks(), &box,
                                     fast, fast ? &ws->gap_written : nullptr,
                                     winkler_slip ? &ws->render_summary : nullptr);
      if (!fast) ws->gap_written = CellBox::All(grid);  // the reference cleared it all
      if (ws->render_time_s) *ws->render_time_s += ThreadCpuSeconds() - t0;
      return level;
    };
    double cull = render(cull_rel);
    double solved_approach = 0.0;  // winkler_slip: the field to write
    CellBox u_region;  // elastic: the region of the check's K p (ws->elastic.check_u)
    for (int pass = 0; pass < 2 && !touching; ++pass) {
      if (pass == 1) cull = render(kInf);
      // (winkler_slip: from the render's summary of the covered cells, else
      // the solve's first pass; MinGap fixes a zero's sign)
      double gmin;
      if (!winkler_slip) {
        gmin = MinGap(grid, box, ws->gap, ws->coverage);
      } else if (RenderSummary& rs = ws->render_summary; rs.valid && rs.gap_min_m != 0.0) {
        gmin = tf.scan_gmin = rs.gap_min_m;  // covered cells: finite gaps
        tf.scan_covmax = rs.coverage_max;
        std::swap(tf.scratch_spans, rs.spans);  // (the next render clears rs.spans)
      } else {
        gmin = ScanWinklerCandidates(grid, ws->gap, ws->coverage, box, &tf);
        if (gmin == 0.0) gmin = MinGap(grid, box, ws->gap, ws->coverage);
      }
      if (!std::isfinite(gmin)) break;
      double approach = 0.0;
      if (cfg.pressure_model == PressureModel::kWinkler) {
        const double guess = warm ? gmin + depth_prev : std::nan("");
        if (winkler_slip) {
          touching = SolveWinkler(grid, ws->gap, ws->coverage, box, cfg.stiffness_pa_per_m,
                                  in.normal_force_n, guess, &tf, &approach, true);
          solved_approach = approach;
        } else {
          touching = (fast ? WinklerPressure : WinklerPressureReference)(
              grid, ws->gap, ws->coverage, box, cfg.stiffness_pa_per_m, in.normal_force_n,
              guess, &tf);
          approach = tf.approach_m;
        }
      } else {
        const ElasticContact& ec = *model.elastic();
        CellBox solve_box = box;  // cold: uniform from the whole rendered box
        if (!warm) ws->pressure_guess.assign(grid.Size(), 0.0);
        ElasticSolveStats st;
        touching = SolveElasticWarm(grid, ec, box, ws->coverage, history ? taxel : nullptr,
                                    in.normal_force_n, ElasticOptions(cfg), &ws->gap,
                                    &ws->pressure_guess, &ws->elastic, &st, &solve_box,
                                    &u_region);
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
        if (!winkler_slip) ClearTraction(grid, &tf);
        continue;
      }
      if (touching) {
        state[kStContactDepth] = approach - gmin;
      }
    }
    // The taxel grid's solution and the check's K p (NormalizeLoad's
    // rescaling is rounding-level) for the next step's warm start.
    if (touching && history)
      StoreElasticHistory(grid, tf.pressure_pa, tf.box, u_region, ws->elastic.check_u,
                          state[kStContactDepth], &taxel[0]);
    // `grid_shift`: average with the solve on the half-cell shifted grid
    // (grid_shift.h), warm-started from its own history; the taxel grid's
    // history keeps the taxel grid's own solution. If the shifted solve
    // fails (it carries the same load on nearly the same cells), the taxel
    // grid's solution stands.
    if (touching && model.shifted()) {
      AverageWithShiftedGrid(*model.shifted(), grid, in.pad_pose, in.surfaces,
                             in.normal_force_n, state[kStContactDepth], ElasticOptions(cfg),
                             fast, shifted_history ? shifted : nullptr, &ws->grid_shift, &tf);
    }
    if (winkler_slip) {
      // the solve's field, or (no contact) the cleared one
      if (touching) {
        // pressure_pa for the `pressure` output; the rest on demand
        // (MaterializeTraction: the stress stage, the Python stage readers)
        touching = WriteWinklerSlipTraction(grid, box, solved_approach, in.normal_force_n,
                                            in.shear_x_n, in.shear_y_n,
                                            cfg.outputs[kOutPressure], &tf);
        finished = true;
      } else {
        ClearTraction(grid, &tf);
      }
    } else if (touching && cfg.shear) {
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
  }
  return touching;
}

}  // namespace mjtouch
