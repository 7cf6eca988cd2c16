// Stage 2: contact pressure and shear traction on the taxel grid, consistent
// with MuJoCo's contact force: the sum of pressure * cell area equals the
// normal force and the sum of shear * cell area the tangential force (to
// round-off, in double precision). Three pressure models, an accuracy
// ladder chosen per scene by the `pressure` attribute:
//   contacts  MuJoCo's contact points splatted onto the grid (no geometry);
//   winkler   elastic foundation: p proportional to the local overlap;
//   elastic   boundary-element contact on the skin's surface compliance
//             (contact_solver.h).
#ifndef MJTOUCH_CONTACT_PRESSURE_H_
#define MJTOUCH_CONTACT_PRESSURE_H_

#include <string>
#include <vector>

#include "common/grid.h"

namespace mjtouch {

enum class PressureModel { kContacts = 0, kWinkler, kElastic };
const char* PressureModelName(PressureModel m);

// Every array is n*n, row-major (j * n + i), and zero outside `box`: the
// per-step work of stage 2 is over the box only (the contact's candidate
// cells), not the whole grid.
struct TractionField {
  std::vector<double> pressure_pa;  // Pa, into the skin (the output)
  std::vector<double> shear_x_pa;   // Pa, along pad x
  std::vector<double> shear_y_pa;   // Pa, along pad y
  // float copies for the stress kernel (kernel.h)
  std::vector<float> pressure, shear_x, shear_y;
  CellBox box;            // support of every array
  ActiveRuns runs;        // cells with nonzero traction, by grid row
  double approach_m = 0;  // solved rigid approach of the pad
  int active_cells = 0;
  // Set by UniformSlipShear: shear = slip ratio x pressure in every cell,
  // which lets stage 3 fold its tables (stress/stress_fold.h). Only
  // UniformSlipShear writes shear in the models that set it.
  bool uniform_slip = false;
  double slip_x = 0, slip_y = 0;  // shear / pressure along pad x, y
  // Every array is zero outside `runs` (FinishUniformSlipTraction), so
  // ClearTraction clears the runs alone, not the whole box.
  bool support_in_runs = false;
  // Arrays WriteWinklerSlipTraction left unwritten (the step's consumers
  // did not need them): zero everywhere until MaterializeTraction derives
  // them from the solve's loads (scratch_load x lazy_scale on `runs`).
  bool lazy_pressure_pa = false;
  bool lazy_shear = false;  // shear_x_pa, shear_y_pa, shear_x, shear_y
  double lazy_scale = 0;
  // Solver scratch (no meaning between calls): the reference's packed
  // candidates; SolveWinkler's candidate spans per row, touching cells
  // (runs, box order), their loads cov (c - gap) (n*n, by cell, written on
  // the touching cells only) and the loads' sum; the last support's runs
  // (WriteWinklerSlipTraction).
  std::vector<double> scratch_gap, scratch_cov, scratch_load;
  ActiveRuns scratch_spans, solved_runs, scratch_runs;
  std::vector<int> scratch_counts;  // SolveWinkler: nonzero loads per span
  double solved_total = 0;
  double scan_gmin = 0, scan_covmax = 0;  // ScanWinklerCandidates
};

// Size every array to the grid and zero the last support: an empty field.
void ClearTraction(const TaxelGrid& grid, TractionField* field);

// A MuJoCo contact on the pad, in the pad frame: position (m) and the force
// on the pad (N; z along the pad's +z, i.e. pressing into the skin).
struct ContactPoint {
  double x_m = 0, y_m = 0;
  double force_n[3] = {0, 0, 0};
};

// `contacts` model: each contact's force spread bilinearly onto the four
// cells around its position (clamped into the grid), divided by the cell
// area: pressure from the force's pad-z component, shear from its pad-x/y
// components. Sums equal the contacts' total force exactly. Returns false
// if the total normal force is not positive.
bool SplatContacts(const TaxelGrid& grid, const std::vector<ContactPoint>& contacts,
                   TractionField* out);

// Winkler (elastic foundation) pressure p = k * coverage * max(c - gap, 0),
// with the approach c solved so that sum(p * A) = normal_force_n exactly (up
// to round-off). The pressure's shape depends on k only through the contact
// size. `approach_guess_m` warm-starts the solve (pass NaN for none). Cells
// outside `box` are not candidates. Returns false (and an all-zero field)
// if no cell can touch.
bool WinklerPressure(const TaxelGrid& grid, const std::vector<double>& gap_m,
                     const std::vector<double>& coverage, const CellBox& box,
                     double stiffness_pa_per_m, double normal_force_n, double approach_guess_m,
                     TractionField* out);

// WinklerPressure's solve alone: the approach (*approach_m), the touching
// cells and their unscaled loads (scratch); the fields are left as they are.
// False if no cell touches. `scanned`: ScanWinklerCandidates ran on the same
// arrays and box (its results in `out` are used, not computed again).
bool SolveWinkler(const TaxelGrid& grid, const std::vector<double>& gap_m,
                  const std::vector<double>& coverage, const CellBox& box,
                  double stiffness_pa_per_m, double normal_force_n, double approach_guess_m,
                  TractionField* out, double* approach_m, bool scanned = false);
// SolveWinkler's first pass over the box (into `out`'s scratch); returns the
// smallest gap of the cells with coverage > 0, as a row-by-row minimum would
// find it up to the sign of a zero.
double ScanWinklerCandidates(const TaxelGrid& grid, const std::vector<double>& gap_m,
                             const std::vector<double>& coverage, const CellBox& box,
                             TractionField* out);

// After SolveWinkler (approach c, on `box`): what WinklerPressure then
// FinishUniformSlipTraction would leave on a field cleared by ClearTraction,
// bit for bit, in two passes over the touching cells, and without
// ClearTraction: `out` may hold the last step's field (zero outside its
// support), of which only the cells outside the new runs are cleared.
// Writes the float pressure, and pressure_pa if `write_pressure_pa`; the
// other arrays are left lazy (zero) for MaterializeTraction.
// False (and the field cleared) if the load is not positive.
bool WriteWinklerSlipTraction(const TaxelGrid& grid, const CellBox& box, double approach_m,
                              double normal_force_n, double ft_x_n, double ft_y_n,
                              bool write_pressure_pa, TractionField* out);

// Writes the arrays WriteWinklerSlipTraction left lazy, of those asked for
// (pressure_pa; the shear arrays, double and float), with the values it
// would have written; nothing for arrays already written.
void MaterializeTraction(const TaxelGrid& grid, bool pressure_pa, bool shear, TractionField* field);

// The same solve without the fast path's shortcuts (every pass over every
// candidate, then NormalizeLoad's scaling): the reference WinklerPressure is
// tested and benchmarked against; the results are bit-identical. The closed
// form's sums and the load's sum are taken in four lanes (WinklerLaneSum).
bool WinklerPressureReference(const TaxelGrid& grid, const std::vector<double>& gap_m,
                              const std::vector<double>& coverage, const CellBox& box,
                              double stiffness_pa_per_m, double normal_force_n,
                              double approach_guess_m, TractionField* out);

// The Winkler solve's sums (closed form, load) in four lanes: lane k adds
// the terms of the cells in columns i = k mod 4 in box order (row by row);
// the sum is (lane 0 + lane 1) + (lane 2 + lane 3). Four independent chains
// let the fast path vectorise them.
inline double WinklerLaneSum(const double lane[4]) {
  return (lane[0] + lane[1]) + (lane[2] + lane[3]);
}

// Full-slip Coulomb shear: q = p * (F_t / F_n) along the direction of
// MuJoCo's friction force (for a rigid pad in gross slip the local slip
// direction is the same everywhere), so that sum(q * A) equals the
// tangential force (ft_x, ft_y) (N, pad frame) to round-off. Cells without
// pressure are left as they are (zero after ClearTraction).
void UniformSlipShear(const TaxelGrid& grid, double normal_force_n, double ft_x_n, double ft_y_n,
                      TractionField* field);

// Scale pressure_pa so that sum * A equals normal_force_n exactly up to
// round-off; returns false (and zeroes it) if the sum is not positive.
bool NormalizeLoad(const TaxelGrid& grid, double normal_force_n, TractionField* out);
// Fill the float copies and the active runs (cells with any traction)
// from the double fields; `shear`: whether the shear fields are loads.
void FinishTraction(const TaxelGrid& grid, bool shear, TractionField* out);
// UniformSlipShear then FinishTraction(shear = true) on a field cleared by
// ClearTraction, in one pass that writes only the loaded cells: the same
// fields bit for bit (a cell is active exactly when its pressure is nonzero,
// since its shear is the pressure times a ratio).
void FinishUniformSlipTraction(const TaxelGrid& grid, double normal_force_n, double ft_x_n,
                               double ft_y_n, TractionField* out);

}  // namespace mjtouch

#endif  // MJTOUCH_CONTACT_PRESSURE_H_
