// Stages 1-2 of the pipeline for one step: render the gap (surface.h) and
// turn it and MuJoCo's contact force into surface tractions (pressure.h,
// contact_solver.h), one function per `pressure` model. Everything depends
// on the step's inputs and `state` only (warm starts come from
// plugin_state), so copies and resets reproduce runs bit for bit.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <tuple>
#include <utility>

#include <time.h>

#include "pipeline/elastic/warm_start.h"
#include "pipeline/skin.h"

namespace mjtouch {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kElasticMaxIterations = 500;
// Winkler + shear (fast paths): the cull level above the smallest gap, in
// last step's indentation depths plus a margin (the other models: 1.5 and
// 20 um). Any level gives the same result (a level the approach reaches
// renders again without culling); a tight one renders and scans fewer cells.
constexpr double kWinklerCullDepths = 1.1, kWinklerCullM = 3e-6;
// shear="partial": full slip from this share of mu P below it up. MuJoCo's
// soft contact holds a sliding pad's friction force up to ~2.5e-5 of mu P
// below the limit, and its small dips would read as unloading (the whole
// contact sticking, Mindlin-Deresiewicz) while the pad slides; the stick
// zone this margin hides is at most (1e-4)^(1/2) = 1% of the area (Winkler).
constexpr double kFullSlipMargin = 1e-4;

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

// CPU time of the calling thread (TractionRunOptions::render_time_s).
double ThreadCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// One step of stage 2, as every pressure model sees it.
struct TractionStep {
  const SkinModel& model;
  const SkinConfig& cfg;
  const StepInput& in;
  const TractionNeeds& needs;
  double* state;
  Workspace* ws;
  bool fast;              // the fast paths (not TractionRunOptions::reference_paths)
  double* render_time_s;  // TractionRunOptions::render_time_s
  bool warm;              // the last step touched: depth_prev_m bounds the render
  double depth_prev_m;    // the last step's indentation depth
  // `elastic`: the pressure history of the taxel grid and of the shifted
  // grid (this time, the last step, the one before); null without one.
  HistoryBlock* taxel;
  HistoryBlock* shifted;
};

// Renders the gap into ws->gap / ws->coverage, culling cells above
// cull_above_m over the smallest gap; `summary`: with the covered cells'
// summary (Winkler + shear). Returns the cull level reached.
double Render(const TractionStep& s, double cull_above_m, bool summary, CellBox* box) {
  Workspace* ws = s.ws;
  const double t0 = s.render_time_s ? ThreadCpuSeconds() : 0.0;
  RenderRequest request{s.cfg.grid,    s.model.skin_z(), s.in.pad_pose,
                        s.in.surfaces, cull_above_m,     &s.model.skin_blocks()};
  request.fast_paths = s.fast;
  RenderOutput out{&ws->gap, &ws->coverage, box};
  out.written = s.fast ? &ws->gap_written : nullptr;
  out.summary = summary ? &ws->render_summary : nullptr;
  out.scratch = &ws->render_scratch;
  const double level = RenderGap(request, out);
  if (!s.fast) ws->gap_written = CellBox::All(s.cfg.grid);  // the reference cleared it all
  if (s.render_time_s) *s.render_time_s += ThreadCpuSeconds() - t0;
  return level;
}

// Renders with cells above cull_rel over the smallest gap culled, then
// solve(box, gmin, &approach) -> touching. A cell whose gap exceeds the
// approach cannot touch (the skin's displacement only adds to the gap), so
// if the solved approach reaches the cull level, everything is rendered and
// solved again (after reset()): the result is exact either way. min_gap(box)
// gives the smallest covered gap (+inf: nothing to touch). Sets the contact
// depth (approach - smallest gap) when touching.
template <typename MinGapFn, typename SolveFn, typename ResetFn>
bool RenderAndSolve(const TractionStep& s, double cull_rel, bool summary, CellBox* box,
                    MinGapFn min_gap, SolveFn solve, ResetFn reset) {
  double cull = Render(s, cull_rel, summary, box);
  bool touching = false;
  for (int pass = 0; pass < 2 && !touching; ++pass) {
    if (pass == 1) cull = Render(s, kInf, summary, box);
    const double gmin = min_gap(*box);
    if (!std::isfinite(gmin)) break;
    double approach = 0.0;
    touching = solve(*box, gmin, &approach);
    if (touching && approach >= cull && pass == 0) {
      touching = false;  // render all and solve again
      reset();
      continue;
    }
    if (touching) s.state[kStContactDepth] = approach - gmin;
  }
  return touching;
}

// The half-space tangential compliance of the skin's top (a layered stack:
// its top layer's; the stick zone's shape depends on nu alone, the shift on
// E too), shared by every simulation of equal grids and moduli.
std::shared_ptr<const TangentialCompliance> SkinTangentialCompliance(const SkinConfig& cfg) {
  const double young = cfg.layered ? cfg.layers[0].young_pa : cfg.young_pa;
  const double nu = cfg.layered ? cfg.layers[0].poisson : cfg.poisson;
  static std::mutex mu;
  static std::map<std::tuple<double, double, double, int>,
                  std::shared_ptr<const TangentialCompliance>>
      cache;
  std::lock_guard<std::mutex> lock(mu);
  auto& slot = cache[{young, nu, cfg.grid.pitch_m, cfg.grid.n}];
  if (!slot)
    slot = std::make_shared<const TangentialCompliance>(young, nu, cfg.grid.pitch_m, cfg.grid.n);
  return slot;
}

// A tangential buffer's box (kTgBox*): its tractions are zero outside it.
// plugin_state is writable from Python, so a box that does not fit the grid
// reads as the whole grid rather than indexing past it.
CellBox TangentialBufferBox(const TaxelGrid& grid, const double* buf) {
  const double i0 = buf[kTgBoxI0], j0 = buf[kTgBoxJ0], nx = buf[kTgBoxNx], ny = buf[kTgBoxNy];
  const double n = grid.n;
  const bool fits = i0 >= 0 && j0 >= 0 && nx >= 0 && ny >= 0 && i0 + nx <= n && j0 + ny <= n;
  if (!fits) return CellBox::All(grid);
  return CellBox{static_cast<int>(i0), static_cast<int>(j0), static_cast<int>(nx),
                 static_cast<int>(ny)};
}

// The tractions x, y (n*n each, after the slots) of buffer `buf` over box b:
// op(buffer x row, buffer y row, row offset in the grid) per row.
template <typename Op>
void ForBufferRows(const TaxelGrid& grid, double* buf, const CellBox& b, Op op) {
  const size_t N = grid.Size();
  double* qx = buf + kTangentialSlots;
  for (int j = b.j0; j < b.j0 + b.ny; ++j) {
    const size_t k = static_cast<size_t>(j) * grid.n + b.i0;
    op(qx + k, qx + N + k, k);
  }
}

// The head buffer into the workspace's TangentialState (zero outside its
// support, which it tracks): cleared over its last support, then the
// buffer's box copied in. Without a valid buffer, zero tractions and shift
// (no memory).
void LoadTangentialState(const TaxelGrid& grid, const double* from, TangentialState* ts) {
  const size_t N = grid.Size();
  if (ts->shear_x_pa.size() != N || ts->shear_y_pa.size() != N || !ts->support_known) {
    ts->shear_x_pa.assign(N, 0.0);
    ts->shear_y_pa.assign(N, 0.0);
  } else {
    const CellBox& b = ts->support;
    for (int j = b.j0; j < b.j0 + b.ny; ++j) {
      const size_t k = static_cast<size_t>(j) * grid.n + b.i0;
      std::fill_n(ts->shear_x_pa.begin() + k, b.nx, 0.0);
      std::fill_n(ts->shear_y_pa.begin() + k, b.nx, 0.0);
    }
  }
  ts->support_known = true;
  ts->support = CellBox{};
  ts->shift_x_m = ts->shift_y_m = 0.0;
  if (!(from[kTgValid] > 0.0)) return;
  ts->support = TangentialBufferBox(grid, from);
  ts->shift_x_m = from[kTgShiftX];
  ts->shift_y_m = from[kTgShiftY];
  ForBufferRows(grid, const_cast<double*>(from), ts->support, [&](double* x, double* y, size_t k) {
    std::copy_n(x, ts->support.nx, ts->shear_x_pa.begin() + k);
    std::copy_n(y, ts->support.nx, ts->shear_y_pa.begin() + k);
  });
}

// Buffer `to`'s tractions zeroed over its box (the rest is zero already).
void ClearTangentialBuffer(const TaxelGrid& grid, double* to) {
  const CellBox old = TangentialBufferBox(grid, to);
  ForBufferRows(grid, to, old, [&](double* x, double* y, size_t) {
    std::fill_n(x, old.nx, 0.0);
    std::fill_n(y, old.nx, 0.0);
  });
}

// Buffer `to`'s slots: valid, the shift (m) and the box its tractions fill.
void WriteTangentialSlots(double shift_x_m, double shift_y_m, const CellBox& b, double* to) {
  to[kTgValid] = 1.0;
  to[kTgShiftX] = shift_x_m;
  to[kTgShiftY] = shift_y_m;
  to[kTgBoxI0] = b.i0;
  to[kTgBoxJ0] = b.j0;
  to[kTgBoxNx] = b.nx;
  to[kTgBoxNy] = b.ny;
}

// The workspace's TangentialState into buffer `to`: its old box cleared,
// the state's support copied, the slots set.
void StoreTangentialState(const TaxelGrid& grid, const TangentialState& ts, double* to) {
  ClearTangentialBuffer(grid, to);
  const CellBox& b = ts.support;
  ForBufferRows(grid, to, b, [&](double* x, double* y, size_t k) {
    std::copy_n(ts.shear_x_pa.begin() + k, b.nx, x);
    std::copy_n(ts.shear_y_pa.begin() + k, b.nx, y);
  });
  WriteTangentialSlots(ts.shift_x_m, ts.shift_y_m, b, to);
}

// shear="partial": whether MuJoCo's force is at the friction limit. Its
// sliding friction reaches mu P to its solver's tolerance (~1e-8): within
// kFullSlipMargin of it the contact slips as a whole (the stick zone left,
// c/a = margin^(1/3) = 1% of the contact, is below any grid) with q = p F / P.
bool PartialFullSlip(const StepInput& in) {
  const double force_t = std::hypot(in.shear_x_n, in.shear_y_n);
  return force_t >= (1.0 - kFullSlipMargin) * in.friction_mu * in.normal_force_n;
}

// shear="partial", on a field holding the uniform-slip shear (shear=true's,
// runs = the loaded cells): in full slip that field stands (stage 3 folds
// it) and becomes the memory; below it, the tangential tractions by Coulomb
// partial slip (tangential.h) replace it on the runs. The memory goes from
// the state's buffer at the head to the buffer this step writes
// (StateLayout); every pass is over the contact's runs or box. On invalid
// input (not expected from MuJoCo's contacts) the uniform field stands.
void PartialSlipTraction(const TractionStep& s) {
  const SkinConfig& cfg = s.cfg;
  const TaxelGrid& grid = cfg.grid;
  const StateLayout& lay = s.model.state_layout();
  Workspace* ws = s.ws;
  TractionField* tf = &ws->traction;
  const double* from = lay.tangential_at(s.state, static_cast<int>(s.state[lay.tangential_head]));
  double* to = lay.tangential_at(s.state, static_cast<int>(s.state[lay.tangential_write]));
  TangentialState& ts = ws->tangential;
  TangentialResult& res = ws->tangential_result;
  const ActiveRuns& runs = tf->runs;
  if (PartialFullSlip(s.in)) {
    res.stick.assign(grid.Size(), 0);
    res.loaded_cells = tf->active_cells;
    res.stick_cells = 0;
    res.stuck_share = 0.0;
    res.full_slip = tf->active_cells > 0;
    res.iterations = res.projection_steps = 0;
    res.change = 0.0;
    const bool valid = from[kTgValid] > 0.0;
    ts.shift_x_m = valid ? from[kTgShiftX] : 0.0;
    ts.shift_y_m = valid ? from[kTgShiftY] : 0.0;
    ClearTangentialBuffer(grid, to);
    const double rx = tf->slip_x, ry = tf->slip_y;
    const size_t N = grid.Size();
    double* qx = to + kTangentialSlots;
    CellBounds bounds;
    for (size_t r = 0; r < runs.row.size(); ++r) {
      const size_t row = static_cast<size_t>(runs.row[r]) * grid.n;
      bounds.AddRow(runs.begin[r], runs.end[r] - 1, runs.row[r]);
      for (size_t k = row + runs.begin[r]; k < row + runs.end[r]; ++k) {
        qx[k] = rx * tf->pressure_pa[k];  // UniformSlipShear's
        qx[N + k] = ry * tf->pressure_pa[k];
      }
    }
    WriteTangentialSlots(ts.shift_x_m, ts.shift_y_m, bounds.Box(), to);
    return;
  }
  LoadTangentialState(grid, from, &ts);
  std::string error;
  bool ok;
  const double mu = s.in.friction_mu;
  if (cfg.pressure_model == PressureModel::kWinkler) {
    const double nu = cfg.layered ? cfg.layers[0].poisson : cfg.poisson;
    ok = SolveTangentialWinkler(grid, tf->pressure_pa, mu, s.in.shear_x_n, s.in.shear_y_n,
                                WinklerTangentialStiffness(cfg.stiffness_pa_per_m, nu), &ts, &res,
                                &error, &tf->box);
  } else {
    if (!ws->tangential_compliance) ws->tangential_compliance = SkinTangentialCompliance(cfg);
    ok = SolveTangentialElastic(grid, tf->pressure_pa, mu, s.in.shear_x_n, s.in.shear_y_n,
                                *ws->tangential_compliance, cfg.tolerance, kElasticMaxIterations,
                                &ts, &res, &error, cfg.elastic_precision, &tf->box);
  }
  if (!ok) {
    res = TangentialResult();
    res.stick.assign(grid.Size(), 0);
    to[kTgValid] = 0.0;
    return;
  }
  // The tractions lie on the loaded cells: the runs.
  for (size_t r = 0; r < runs.row.size(); ++r) {
    const size_t row = static_cast<size_t>(runs.row[r]) * grid.n;
    for (size_t k = row + runs.begin[r]; k < row + runs.end[r]; ++k) {
      tf->shear_x_pa[k] = ts.shear_x_pa[k];
      tf->shear_y_pa[k] = ts.shear_y_pa[k];
      tf->shear_x[k] = static_cast<float>(ts.shear_x_pa[k]);
      tf->shear_y[k] = static_cast<float>(ts.shear_y_pa[k]);
    }
  }
  tf->lazy_shear = false;
  tf->uniform_slip = false;  // stage 3 sums the shear fields
  StoreTangentialState(grid, ts, to);
}

// The shear (full-slip Coulomb, uniform ratio; or partial slip) of a solved
// pressure field, the float copies and the active runs.
void FinishSolvedTraction(const TractionStep& s) {
  const TaxelGrid& grid = s.cfg.grid;
  TractionField* tf = &s.ws->traction;
  const StepInput& in = s.in;
  if (s.cfg.shear && s.cfg.shear_partial) {
    if (s.fast) {
      FinishUniformSlipTraction(grid, in.normal_force_n, in.shear_x_n, in.shear_y_n, tf);
    } else {
      UniformSlipShear(grid, in.normal_force_n, in.shear_x_n, in.shear_y_n, tf);
      FinishTraction(grid, true, tf);
    }
    PartialSlipTraction(s);
  } else if (!s.cfg.shear) {
    FinishTraction(grid, false, tf);
  } else if (!s.fast) {
    UniformSlipShear(grid, in.normal_force_n, in.shear_x_n, in.shear_y_n, tf);
    FinishTraction(grid, true, tf);
  } else {  // the shear and FinishTraction in one pass
    FinishUniformSlipTraction(grid, in.normal_force_n, in.shear_x_n, in.shear_y_n, tf);
  }
}

// `contacts`: MuJoCo's contact points splatted onto the grid.
bool ContactsTraction(const TractionStep& s) {
  TractionField* tf = &s.ws->traction;
  const bool touching = SplatContacts(s.cfg.grid, s.in.contacts, tf);
  s.state[kStContactDepth] = 0.0;
  if (touching) FinishTraction(s.cfg.grid, s.cfg.shear, tf);
  return touching;
}

// `winkler`: the elastic foundation, every array written (the reference
// path, and the fast path without shear).
bool WinklerTraction(const TractionStep& s) {
  const TaxelGrid& grid = s.cfg.grid;
  Workspace* ws = s.ws;
  TractionField* tf = &ws->traction;
  ClearTraction(grid, tf);
  const double cull_rel = s.warm ? CullLevel(s.depth_prev_m) : kInf;
  CellBox box;
  const bool touching = RenderAndSolve(
      s, cull_rel, false, &box,
      [&](const CellBox& b) { return MinGap(grid, b, ws->gap, ws->coverage); },
      [&](const CellBox& b, double gmin, double* approach) {
        const double guess = s.warm ? gmin + s.depth_prev_m : std::nan("");
        const bool t = (s.fast ? WinklerPressure : WinklerPressureReference)(
            grid, ws->gap, ws->coverage, b, s.cfg.stiffness_pa_per_m, s.in.normal_force_n, guess,
            tf);
        *approach = tf->approach_m;
        return t;
      },
      [&] { ClearTraction(grid, tf); });
  if (touching) FinishSolvedTraction(s);
  return touching;
}

// `winkler` with shear, fast path: solved first, then the field written over
// the last one (WriteWinklerSlipTraction), which clears only what the new
// contact does not cover; the arrays no later stage needs stay lazy.
// shear="partial": then the partial-slip shear over the uniform one.
bool WinklerSlipTraction(const TractionStep& s) {
  const TaxelGrid& grid = s.cfg.grid;
  const StepInput& in = s.in;
  Workspace* ws = s.ws;
  TractionField& tf = ws->traction;
  const double cull_rel = s.warm ? kWinklerCullDepths * s.depth_prev_m + kWinklerCullM : kInf;
  CellBox box;
  double solved_approach = 0.0;
  bool touching = RenderAndSolve(
      s, cull_rel, true, &box,
      [&](const CellBox& b) {
        // from the render's summary of the covered cells, else the solve's
        // first pass; MinGap fixes a zero's sign
        RenderSummary& rs = ws->render_summary;
        if (rs.valid && rs.gap_min_m != 0.0) {
          tf.scan_gmin = rs.gap_min_m;  // covered cells: finite gaps
          tf.scan_covmax = rs.coverage_max;
          std::swap(tf.scratch_spans, rs.spans);  // (the next render clears rs.spans)
          return rs.gap_min_m;
        }
        const double gmin = ScanWinklerCandidates(grid, ws->gap, ws->coverage, b, &tf);
        return gmin == 0.0 ? MinGap(grid, b, ws->gap, ws->coverage) : gmin;
      },
      [&](const CellBox& b, double gmin, double* approach) {
        const double guess = s.warm ? gmin + s.depth_prev_m : std::nan("");
        const bool t = SolveWinkler(grid, ws->gap, ws->coverage, b, s.cfg.stiffness_pa_per_m,
                                    in.normal_force_n, guess, &tf, approach, true);
        solved_approach = *approach;
        return t;
      },
      [] {});
  if (touching) {
    // (partial slip reads the pressure)
    touching =
        WriteWinklerSlipTraction(grid, box, solved_approach, in.normal_force_n, in.shear_x_n,
                                 in.shear_y_n, s.needs.pressure_pa || s.cfg.shear_partial, &tf);
    if (touching && s.cfg.shear_partial) PartialSlipTraction(s);
  } else {
    ClearTraction(grid, &tf);
  }
  return touching;
}

// `elastic`: boundary-element contact warm-started from the pressure
// history, with `grid_shift` averaged with the half-cell shifted grid's.
bool ElasticTraction(const TractionStep& s) {
  const SkinConfig& cfg = s.cfg;
  const TaxelGrid& grid = cfg.grid;
  const StepInput& in = s.in;
  Workspace* ws = s.ws;
  TractionField& tf = ws->traction;
  const ElasticSolveOptions options = ElasticOptions(cfg);
  ClearTraction(grid, &tf);
  if (s.model.cycle()) {  // `grid_cycle`: one offset grid per step (grid_cycle.h)
    const StateLayout& lay = s.model.state_layout();
    double depth = 0.0;
    const int length =
        CycleLength(lay.cycle, in.timestep_s / std::max(1, cfg.oversample));  // per evaluation
    const bool touching =
        CycleTraction(*s.model.cycle(), static_cast<int>(s.state[lay.cycle_slot]), length, grid,
                      in.pad_pose, in.surfaces, in.normal_force_n, s.warm, s.depth_prev_m, options,
                      s.fast, s.shifted, &ws->grid_shift, &tf, &depth);
    ws->elastic_stats = ws->grid_shift.stats;
    if (!touching) {
      ClearTraction(grid, &tf);
      return false;
    }
    s.state[kStContactDepth] = depth;
    FinishSolvedTraction(s);
    return true;
  }
  const double cull_rel = s.warm ? CullLevel(s.depth_prev_m) : kInf;
  CellBox box;
  CellBox u_region;  // the region of the check's K p (ws->elastic.check_u)
  bool touching = RenderAndSolve(
      s, cull_rel, false, &box,
      [&](const CellBox& b) { return MinGap(grid, b, ws->gap, ws->coverage); },
      [&](const CellBox& b, double, double* approach) {
        CellBox solve_box = b;  // cold: uniform from the whole rendered box
        if (!s.warm) ws->pressure_guess.assign(grid.Size(), 0.0);
        ElasticSolveStats st;
        bool t = SolveElasticWarm(grid, *s.model.elastic(), b, ws->coverage, s.taxel,
                                  in.normal_force_n, options, &ws->gap, &ws->pressure_guess,
                                  &ws->elastic, &st, &solve_box, &u_region);
        if (t) {
          tf.pressure_pa.swap(ws->pressure_guess);
          tf.box = solve_box;
          t = NormalizeLoad(grid, in.normal_force_n, &tf);
        }
        ws->elastic_stats = st;
        *approach = st.approach_m;
        return t;
      },
      [&] { ClearTraction(grid, &tf); });
  // The taxel grid's solution and the check's K p (NormalizeLoad's
  // rescaling is rounding-level) for the next step's warm start.
  if (touching && s.taxel)
    StoreElasticHistory(grid, tf.pressure_pa, tf.box, u_region, ws->elastic.check_u,
                        s.state[kStContactDepth], &s.taxel[0]);
  // `grid_shift`: average with the solve on the half-cell shifted grid
  // (grid_shift.h), warm-started from its own history; the taxel grid's
  // history keeps the taxel grid's own solution. If the shifted solve
  // fails (it carries the same load on nearly the same cells), the taxel
  // grid's solution stands.
  if (touching && s.model.shifted())
    AverageWithShiftedGrid(*s.model.shifted(), grid, in.pad_pose, in.surfaces, in.normal_force_n,
                           s.state[kStContactDepth], options, s.fast, s.shifted, &ws->grid_shift,
                           &tf);
  if (touching) FinishSolvedTraction(s);
  return touching;
}

}  // namespace

bool ComputeTraction(const SkinModel& model, const StepInput& in, const TractionNeeds& needs,
                     double* state, Workspace* ws, bool new_time, const TractionRunOptions& run) {
  const SkinConfig& cfg = model.config();
  // `elastic`: the last step's contact from the pressure history, so a
  // repeated evaluation at the same time starts where the first one did.
  const StateLayout& lay = model.state_layout();
  const bool history = lay.history_block > 0;
  HistoryBlock taxel[3]{}, shifted[2 * kMaxGridCycle]{};
  const bool cycle = lay.cycle > 1;
  if (history || cycle) {
    if (new_time) {
      state[lay.history_head] = (static_cast<int>(state[lay.history_head]) + 1) % lay.ring;
      if (cycle) state[lay.cycle_slot] = (static_cast<int>(state[lay.cycle_slot]) + 1) % lay.cycle;
    }
    if (history) {
      for (int back = 0; back < 3; ++back) taxel[back] = lay.history_at(state, back);
      taxel[0].slots[kHsValid] = 0.0;
    }
    if (lay.shifted_block > 0) {
      for (int back = 0; back < lay.ring; ++back)
        shifted[back] = lay.shifted_history_at(state, back);
      shifted[0].slots[kHsValid] = 0.0;
    }
  }
  // `grid_cycle`: the last step's depth, whichever grid it solved
  const bool warm = history ? HasWarmStart(taxel)
                    : cycle ? shifted[1].slots[kHsValid] > 0.0
                            : state[kStContactValid] > 0.0;
  const double depth_prev = history ? taxel[1].slots[kHsDepth]
                            : cycle ? shifted[1].slots[kHsDepth]
                                    : state[kStContactDepth];
  state[kStContactValid] = 0.0;
  // shear="partial": the buffer written becomes the head; without contact
  // it holds no memory.
  auto finish = [&](bool touching) {
    if (lay.tangential_block > 0) {
      const int to = static_cast<int>(state[lay.tangential_write]);
      if (!touching) lay.tangential_at(state, to)[kTgValid] = 0.0;
      state[lay.tangential_head] = to;
    }
    if (touching) state[kStContactValid] = 1.0;
    return touching;
  };
  if (!(in.in_contact && in.normal_force_n > 0.0)) return finish(false);
  const bool contacts = cfg.pressure_model == PressureModel::kContacts;
  if (!contacts && in.surfaces.empty()) return finish(false);

  const TractionStep step{model,
                          cfg,
                          in,
                          needs,
                          state,
                          ws,
                          !run.reference_paths,
                          run.render_time_s,
                          warm,
                          depth_prev,
                          history ? taxel : nullptr,
                          lay.shifted_block > 0 ? shifted : nullptr};
  bool touching;
  switch (cfg.pressure_model) {
    case PressureModel::kContacts: touching = ContactsTraction(step); break;
    case PressureModel::kWinkler:
      touching = step.fast && cfg.shear ? WinklerSlipTraction(step) : WinklerTraction(step);
      break;
    default: touching = ElasticTraction(step); break;
  }
  return finish(touching);
}

}  // namespace mjtouch
