// `grid_shift`: the `elastic` contact solved a second time on the
// taxel grid shifted by half a cell in x and y (n + 1 cells: centres at the
// taxel grid's cell corners), deposited back onto the taxel grid (each
// shifted cell's load split equally over the 4 cells it overlaps, which
// keeps its total and centroid) and averaged with the first solution.
//
// Why: texture features narrower than a cell (the default grating's edges
// are rounded over 50 um; the edge pressure peaks are narrower still) make
// the discrete contact's error periodic in the texture's offset against the
// grid; sliding at V that is a line at V / pitch (and harmonics) in the
// receptor stress (250 Hz at 0.1 mm, 25 mm/s: PC's best frequency), which a
// finer pitch moves, not removes. Half a cell flips the sign of the error's
// first Fourier component, so the average cancels the V / pitch line; the
// physical lines at m V / D are kept (examples/pc_grid_line_static.py,
// examples/pc_grid_shift.py). Cost: a second render and solve per step,
// warm-started from the shifted grid's own history in plugin_state (state_layout.h)
// like the taxel grid's solve.
#ifndef MJTOUCH_PIPELINE_ELASTIC_GRID_SHIFT_H_
#define MJTOUCH_PIPELINE_ELASTIC_GRID_SHIFT_H_

#include <memory>
#include <vector>

#include "common/grid.h"
#include "contact/contact_solver.h"
#include "contact/pressure.h"
#include "pipeline/elastic/warm_start_work.h"
#include "surface/surface.h"

namespace mjtouch {

struct HistoryBlock;  // state_layout.h

// The shifted grid's immutable tables (SkinModel, with `grid_shift`).
struct ShiftedGrid {
  TaxelGrid grid;              // n + 1 cells of the taxel grid's pitch
  std::vector<double> skin_z;  // SkinSurface on it
  SkinBlocks blocks;
  std::shared_ptr<const ElasticContact> elastic;  // the skin's compliance on it
};

// Per-simulation scratch (Workspace).
struct GridShiftWork {
  std::vector<double> gap, coverage, pressure;
  CellBox gap_written;  // the cells of gap / coverage not +inf / 0 (grid_cycle)
  RenderScratch render_scratch;
  ElasticStepWork elastic;
  ElasticSolveStats stats;
  std::vector<double> deposit_row;  // grid_cycle's deposit, one row
  std::vector<float> deposit_row_f;
};

// field: the taxel grid's solution (pressure_pa on field->box, its total
// force_n). Solves the contact on the shifted grid (rendered with the same
// cull rule as the taxel grid, again without culling if the solved approach
// reaches it, so the result is exact on the rendered cells), warm-started
// from history (the shifted grid's blocks of plugin_state: this time, the
// last step, the one before; null: none) as the taxel grid's solve, or
// without a last step from the taxel grid's solution; writes this step's
// shifted solution to history[0]; writes the average to field (box grown
// by one cell, load normalised to force_n). If the shifted grid renders no
// contact, the field is left as it was. Returns false if the shifted solve
// fails to carry the load (the field is then left as it was; history[0]
// stays invalid in both cases).
bool AverageWithShiftedGrid(const ShiftedGrid& sg, const TaxelGrid& grid, const Pose& pad_pose,
                            const std::vector<CounterSurface>& surfaces, double force_n,
                            double depth_m, const ElasticSolveOptions& options, bool fast_paths,
                            HistoryBlock* history, GridShiftWork* w, TractionField* field);

}  // namespace mjtouch

#endif  // MJTOUCH_PIPELINE_ELASTIC_GRID_SHIFT_H_
