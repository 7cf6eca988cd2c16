// Scratch of the `elastic` step's solve sequence (warm_start.h): the
// solver's own (ElasticWork) and the warm start's and box check's, which
// belong to the pipeline, not to the contact solver. Per simulation, no
// state that outlives a call (Workspace, GridShiftWork).
#ifndef MJTOUCH_PIPELINE_ELASTIC_WARM_START_WORK_H_
#define MJTOUCH_PIPELINE_ELASTIC_WARM_START_WORK_H_

#include <vector>

#include "contact/contact_solver.h"

namespace mjtouch {

struct ElasticStepWork {
  ElasticWork solve;
  // the box check: the pressure on its box (zero off the solve box), and
  // K p there (the next steps' warm-start displacement)
  std::vector<double> check_p, check_u;
  std::vector<double> u0;         // K times the extrapolated guess on the solve box
  std::vector<int> u0_fix;        // grid cells where the guess is not 2 p(n-1) - p(n-2)
  std::vector<int> fix_i, fix_j;  // u0_fix's cells in box coordinates
  std::vector<double> fix_d;      // and their corrections (Pa)
  std::vector<double> warm_lin;   // 2 p(n-1) - p(n-2) on the history boxes' union (Pa)
  std::vector<float> row_f;       // history rows as stored (Pa)
};

}  // namespace mjtouch

#endif  // MJTOUCH_PIPELINE_ELASTIC_WARM_START_WORK_H_
