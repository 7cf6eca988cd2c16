// The `elastic` solve's warm start from the pressure history (model.h,
// HistoryBlock) and its box-growing solve, shared by the taxel grid's solve
// and the half-cell shifted grid's (grid_shift.cc); defined in
// skin_traction.cc.
#ifndef MJTOUCH_PIPELINE_WARM_START_H_
#define MJTOUCH_PIPELINE_WARM_START_H_

#include <vector>

#include "pipeline/model.h"

namespace mjtouch {

// Cells [i0, i1] x [j0, j1] widened by kBoxMarginCells, clipped to box
// (empty if they miss it).
CellBox GrowBox(const CellBox& box, int i0, int i1, int j0, int j1);

// Smallest gap over the covered cells of the box (+inf if none).
double MinGap(const TaxelGrid& grid, const CellBox& box, const std::vector<double>& gap,
              const std::vector<double>& cov);

// The warm start (`last` null: cold): *guess = the last step's pressure, or
// with `prev` max(0, 2 p(n-1) - p(n-2)); *solve_box = the last contact
// kBoxMarginCells wider (within box); with `prev`, the cells where the guess
// on *solve_box differs from 2 p(n-1) - p(n-2) (clipped, or outside the box)
// in w->u0_fix (ExtrapolatedDisplacement).
void WarmStart(const TaxelGrid& grid, const CellBox& box, const HistoryBlock* last,
               const HistoryBlock* prev, std::vector<double>* guess, ElasticWork* w,
               CellBox* solve_box);

// w->u0 = K times the extrapolated guess on `box` from the last two steps'
// stored K p (linear), corrected where WarmStart clipped; false (apply the
// operator instead) if the stored displacements do not cover `box`.
bool ExtrapolatedDisplacement(const TaxelGrid& grid, const SurfaceCompliance& K,
                              const HistoryBlock& last, const HistoryBlock& prev,
                              const std::vector<double>& guess, const CellBox& box,
                              ElasticWork* w);

// Solves the contact on *solve_box from *pressure (u0: K *pressure there, or
// null), checks that no rendered cell of `box` outside it could touch
// (the skin's lift bound lift_m) and grows it around the cells that would,
// after kBoxAttempts on all of `box`. Returns whether the load is carried;
// *solve_box is the final box, *u_region the box over which w->check_u holds
// K p of the solution (nx = 0: none), which the next step's warm start uses.
bool SolveOnGrowingBox(const TaxelGrid& grid, const ElasticContact& ec,
                       const std::vector<double>& gap, const CellBox& box, double force_n,
                       double lift_m, double tolerance, int max_iterations,
                       ElasticMethod method, ApplyPrecision precision, const double* u0,
                       std::vector<double>* pressure, ElasticWork* w, ElasticSolveStats* st,
                       CellBox* solve_box, CellBox* u_region);

}  // namespace mjtouch

#endif  // MJTOUCH_PIPELINE_WARM_START_H_
