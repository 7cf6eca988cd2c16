// `grid_cycle` N: the `elastic` contact solved each step on one of N grids
// of n + 1 cells whose centres sit k / N of a cell (k = 0 .. N - 1) off the
// taxel grid's corners in x and y, in turn; the traction is the average of
// the N latest solutions, each deposited on the nearest taxel cells (the
// average keeps the total and first moment: grid_cycle.cc, DepositOf).
//
// Why: texture edges sharper than a cell lose their sub-cell position in a
// discrete contact, so its error is periodic in the texture's offset
// against the grid: a line at V / pitch and its harmonics in the receptor
// stress (250 Hz at 0.1 mm and 25 mm/s, PC's best frequency). Offsets k / N
// cancel the error's first N - 1 harmonics in the average, as `grid_shift`
// cancels the first with two solves per step; here each step solves one
// grid, warm-started from that grid's own solution N steps back.
// The average is of the grids' solutions at one time, N - 1 steps back
// (each interpolated between its last two): the traction lags the pad by
// 0.3 ms at N = 4 and dt = 0.1 ms.
#ifndef MJTOUCH_PIPELINE_ELASTIC_GRID_CYCLE_H_
#define MJTOUCH_PIPELINE_ELASTIC_GRID_CYCLE_H_

#include <memory>
#include <vector>

#include "pipeline/elastic/grid_shift.h"

namespace mjtouch {

// The offset grids (SkinModel, `grid_cycle` > 1): grids[k] has n + 1 cells,
// offset_m = k pitch / N from the taxel grid's corners.
struct CycleGrids {
  std::vector<ShiftedGrid> grids;
};

// The longest cycle (s): with a longer timestep fewer grids cycle (a
// divisor of N), so that the cycle's own frequency 1 / (N dt), where what
// is left of the grid's error is modulated, stays above PC's band.
constexpr double kMaxCyclePeriodS = 0.5e-3;

// How many of the N grids cycle at evaluation interval dt_s (0: unknown,
// all of them).
int CycleLength(int n_grids, double dt_s);

// One step: `slot` counts steps modulo N; `length` grids cycle (a divisor
// of N: every N / length-th grid, the taxel-centred one k = N / 2 among
// them). Solves this step's grid (rendered with the cull level of
// depth_prev_m if warm, else everything; again without culling if the
// solved approach reaches it) to length times options' tolerance,
// warm-started from its own solution length steps back (ring[b]: the history block b steps back, b
// = 0 .. 2 N - 1; ring[0] is written), then writes to field (cleared by the caller) the average
// over the cycling grids of each one's solution at length - 1 steps back, interpolated between its
// last two (ring[0 .. 2 length - 1]; solutions of another indentation depth left out), load
// normalised to force_n. *depth_m:
// this step's indentation depth. Returns whether the contact carries the
// load.
bool CycleTraction(const CycleGrids& cg, int slot, int length, const TaxelGrid& grid,
                   const Pose& pad_pose, const std::vector<CounterSurface>& surfaces,
                   double force_n, bool warm, double depth_prev_m,
                   const ElasticSolveOptions& options, bool fast_paths, HistoryBlock* ring,
                   GridShiftWork* w, TractionField* field, double* depth_m);

}  // namespace mjtouch

#endif  // MJTOUCH_PIPELINE_ELASTIC_GRID_CYCLE_H_
