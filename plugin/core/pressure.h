// Stage 2: contact pressure and shear traction on the taxel grid, consistent
// with MuJoCo's contact force: the sum of pressure * cell area equals the
// normal force and the sum of shear * cell area the tangential force.
#ifndef MJTOUCH_CORE_PRESSURE_H_
#define MJTOUCH_CORE_PRESSURE_H_

#include <vector>

#include "grid.h"
#include "kernel.h"

namespace mjtouch {

struct TractionField {
  std::vector<float> pressure;  // Pa, n*n, into the skin
  std::vector<float> shear_x;   // Pa, n*n, along pad x
  std::vector<float> shear_y;   // Pa, n*n, along pad y
  ActiveRuns runs;              // cells with nonzero pressure, by grid row
  double approach_m = 0;        // solved rigid approach of the pad
  int active_cells = 0;
};

// Winkler (elastic foundation) pressure p = k * coverage * max(c - gap, 0),
// with the approach c solved so that sum(p * A) = normal_force_n exactly (up
// to round-off). The pressure's shape depends on k only through the contact
// size. `approach_guess_m` warm-starts the solve (pass NaN for none).
// Returns false (and an all-zero field) if no cell can touch.
bool WinklerPressure(const TaxelGrid& grid, const std::vector<double>& gap_m,
                     const std::vector<double>& coverage, double stiffness_pa_per_m,
                     double normal_force_n, double approach_guess_m,
                     TractionField* out);

// Full-slip shear traction: q = p * (F_t / F_n), so that sum(q * A) equals the
// tangential force (ft_x, ft_y) (N, pad frame) exactly.
void UniformSlipShear(const TaxelGrid& grid, double normal_force_n, double ft_x_n,
                      double ft_y_n, TractionField* field);

}  // namespace mjtouch

#endif  // MJTOUCH_CORE_PRESSURE_H_
