// Stage 3, per step, fast path: hierarchical (Barnes-Hut) summation of the
// lattice tables of kernel.h. The taxel grid is cut into a quadtree of cell
// blocks (1, 2, 4, ... cells a side). For each receptor a fixed list of blocks
// covers the grid: a block of side b whose centre lies at distance R from the
// receptor (depth included) is one term when b <= theta R, else its four
// children are visited. Over a block the table is replaced by its
// least-squares plane K ~ K0 + K1x X + K1y Y (X, Y: cell offsets from the
// block centre), so a term is K0 T + K1x Mx + K1y My with the block's traction
// sum T and first moments Mx, My (monopole + dipole). The error is the
// table's curvature over the block, ~ (b / R)^2: RMS 3e-4 (0.75 mm) to 1e-3
// (2 mm) of the stress at theta = 0.5 on the default contact, 3e-5 to 1e-4 at
// 0.25 (measured against direct summation; tests/test_stress_tree.py). The
// lists and coefficients are built once per model; per step only the block
// moments of the active bounding box are formed (O(active cells)), then
// ~20-250 terms per receptor instead of one per active cell. Deterministic:
// fixed order, no data-dependent paths. Pure C++: no MuJoCo types.
#ifndef MJTOUCH_STRESS_STRESS_TREE_H_
#define MJTOUCH_STRESS_STRESS_TREE_H_

#include <cstdint>
#include <memory>
#include <vector>

#include "stress/kernel_tables.h"

namespace mjtouch {

// Hierarchical path's per-step block moments .
struct TreeScratch {
  std::vector<std::vector<float>> moments;  // [level][(bj * nb + bi) * 9 + 3 * load + m]
  std::vector<int> box;                     // [4 level + (i0, i1, j0, j1)], inclusive
};

class StressTree {
 public:
  // theta > 0. `shear`: whether shear tractions load the skin (else only
  // pressure coefficients are built). Sites as for ComputeStresses.
  static std::shared_ptr<const StressTree> Build(const KernelTables& kt,
                                                 const std::vector<StressSite>& sites, bool shear,
                                                 double theta);

  // Stress (Pa) at every site into out[site] (unwanted components 0). Shear
  // arrays may be null (both or neither); if the tree was built without
  // shear they are ignored. runs: the active cells (FindActiveRuns).
  void Compute(const ActiveRuns& runs, const float* pressure, const float* shear_x,
               const float* shear_y, TreeScratch* scratch, Stress6* out) const;

  double theta() const { return theta_; }
  int loads() const { return loads_; }
  // Mean number of terms per site (blocks summed), for cost reports.
  double mean_terms() const;
  double build_seconds() const { return build_seconds_; }

 private:
  struct SiteTerms {
    std::vector<uint32_t> block;  // level << 24 | bj << 12 | bi
    std::vector<float> coef;      // per term: [load][moment][comp slot], 8 comp slots
    int comps[kNumStress];        // wanted components, in slot order
    int ncomp = 0;
  };
  // Clipped block geometry along one axis at one level: cells [lo, hi).
  int BlockLo(int level, int b) const { return b << level; }
  int BlockHi(int level, int b) const { return std::min(n_, (b + 1) << level); }
  double BlockCentre(int level, int b) const {
    return 0.5 * (BlockLo(level, b) + BlockHi(level, b) - 1);
  }
  int Blocks(int level) const { return (n_ + (1 << level) - 1) >> level; }

  int n_ = 0;
  int levels_ = 0;  // levels 0 .. levels_ - 1; the top level is one block
  int loads_ = 1;
  double theta_ = 0;
  double build_seconds_ = 0;
  std::vector<SiteTerms> sites_;
};

}  // namespace mjtouch

#endif  // MJTOUCH_STRESS_STRESS_TREE_H_
