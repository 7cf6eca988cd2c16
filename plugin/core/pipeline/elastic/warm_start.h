// The `elastic` solve of one step, shared by the taxel grid's solve
// (skin_traction.cc) and the half-cell shifted grid's (grid_shift.cc): the
// cull level, the warm start from the pressure history (state_layout.h,
// HistoryBlock), the solve on a growing box and the history write; defined
// in warm_start.cc.
#ifndef MJTOUCH_PIPELINE_ELASTIC_WARM_START_H_
#define MJTOUCH_PIPELINE_ELASTIC_WARM_START_H_

#include <vector>

#include "pipeline/elastic/warm_start_work.h"
#include "pipeline/model.h"

namespace mjtouch {

// Cells [i0, i1] x [j0, j1] widened by kBoxMarginCells, clipped to box
// (empty if they miss it).
CellBox GrowBox(const CellBox& box, int i0, int i1, int j0, int j1);

// Smallest gap over the covered cells of the box (+inf if none).
double MinGap(const TaxelGrid& grid, const CellBox& box, const std::vector<double>& gap,
              const std::vector<double>& cov);

// The render's cull level above the smallest gap (m) from an indentation
// depth (m): cells above it are not rendered. Any level gives the same
// result (if the solved approach reaches it, the caller renders everything
// and solves again); a tight one renders fewer cells.
inline double CullLevel(double depth_m) { return 1.5 * depth_m + 20e-6; }

// Whether history (this time, the last step, the one before; null: none)
// holds a last step to warm-start from.
bool HasWarmStart(const HistoryBlock* history);

// One step's contact solve on the rendered cells `box`: cells without
// coverage get gap +inf (they never touch); the warm start from history (as
// HasWarmStart; with contact_solver = pcg and a valid step before,
// extrapolated 2 p(n-1) - p(n-2), with its K p from the stored ones), else
// from *pressure and *solve_box as the caller set them; then solved on a
// box grown until no rendered cell outside it can touch. Returns whether
// the load is carried; *solve_box is the final box, *u_region the box over
// which w->check_u holds K p of the solution (nx = 0: none).
bool SolveElasticWarm(const TaxelGrid& grid, const ElasticContact& ec, const CellBox& box,
                      const std::vector<double>& coverage, const HistoryBlock* history,
                      double force_n, const ElasticSolveOptions& options, std::vector<double>* gap,
                      std::vector<double>* pressure, ElasticStepWork* w, ElasticSolveStats* st,
                      CellBox* solve_box, CellBox* u_region);

// A history block's solution and its weight in a warm start.
struct WarmTerm {
  const HistoryBlock* block;
  double weight;
};

// SolveElasticWarm from any weighted sum of stored solutions of this grid
// (terms[0]'s contact sets the first solve box; one term: that solution;
// none: from *pressure and *solve_box as the caller set them), the guess
// clipped at zero and its K p from the stored ones (one term: only with
// single_term_u, else the solve applies the operator).
bool SolveElasticWarmFrom(const TaxelGrid& grid, const ElasticContact& ec, const CellBox& box,
                          const std::vector<double>& coverage, const WarmTerm* terms, int nterms,
                          bool single_term_u, double force_n, const ElasticSolveOptions& options,
                          std::vector<double>* gap, std::vector<double>* pressure,
                          ElasticStepWork* w, ElasticSolveStats* st, CellBox* solve_box,
                          CellBox* u_region);

// Writes a solution to a history block: the pressure on p_box (zero
// outside it), its K p u over u_region (row-major), the depth; marks it valid.
void StoreElasticHistory(const TaxelGrid& grid, const std::vector<double>& pressure,
                         const CellBox& p_box, const CellBox& u_region,
                         const std::vector<double>& u, double depth_m, HistoryBlock* cur);

}  // namespace mjtouch

#endif  // MJTOUCH_PIPELINE_ELASTIC_WARM_START_H_
