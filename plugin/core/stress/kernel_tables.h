// Stage 3: lattice influence tables of a substrate for the taxel grid, and
// direct summation of surface tractions to the stress at one receptor.
#ifndef MJTOUCH_STRESS_KERNEL_TABLES_H_
#define MJTOUCH_STRESS_KERNEL_TABLES_H_

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "common/grid.h"
#include "substrate/substrate.h"

namespace mjtouch {

// Lattice tables for a set of depths, shared read-only by every MjData of one
// model (built once per distinct configuration).
struct KernelTables {
  int n = 0;                                  // taxel grid is n x n
  double pitch_m = 0;                         // taxel pitch
  std::vector<double> depths_m;               // one table per depth
  std::vector<std::vector<float>> tables;     // layout as Substrate::LatticeTable
  std::array<bool, kNumStress> components{};  // components filled
  // Every table even or odd under x -> -x and y -> -y as a laterally
  // isotropic substrate's must be (MirrorSign), to 1e-6 of its largest
  // entry: the folded path then reads only offsets >= 0 (stress_fold.h).
  bool mirror_symmetric = false;
  double build_seconds = 0;

  const float* At(int depth_index, SurfaceLoad load, StressComponent comp) const {
    const int L = 2 * n - 1;
    return tables[depth_index].data() + static_cast<size_t>(load * kNumStress + comp) * L * L;
  }
};

// One receptor site: taxel cell above it, its depth's table, and the stress
// components its receptor quantity needs.
struct StressSite {
  int i = 0, j = 0;
  int depth_index = 0;
  std::array<bool, kNumStress> want{};
};

// Sign s with K(load, comp) at (-dx, dy) = s K at (dx, dy) (axis 0), or at
// (dx, -dy) (axis 1): shear along an axis and the stresses xy, xz (x) / xy,
// yz (y) are odd under that axis's reflection, everything else even.
inline float MirrorSign(int axis, SurfaceLoad load, StressComponent comp) {
  const bool odd_load = load == (axis == 0 ? kLoadShearX : kLoadShearY);
  const bool odd_comp = comp == kSxy || comp == (axis == 0 ? kSxz : kSyz);
  return odd_load != odd_comp ? -1.0f : 1.0f;
}

std::shared_ptr<const KernelTables> BuildKernelTables(
    const Substrate& substrate, int n, double pitch_m, const std::vector<double>& depths_m,
    const std::array<bool, kNumStress>& components);

// Stress at one receptor (grid cell index ri, rj, table `depth_index`) from
// the tractions of the active cells. Direct summation over the active cells'
// row runs. pressure/shear arrays are n*n, row-major (j * n + i), Pa.

void StressAtReceptor(const KernelTables& kt, int depth_index, int ri, int rj,
                      const ActiveRuns& runs, const float* pressure, const float* shear_x,
                      const float* shear_y, const std::array<bool, kNumStress>& want, Stress6* out);

}  // namespace mjtouch

#endif  // MJTOUCH_STRESS_KERNEL_TABLES_H_
