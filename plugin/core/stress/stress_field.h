// Stage 3, per step: the stress tensor at receptor sites from the surface
// tractions, through the lattice tables of kernel.h, by one of three paths:
//  - direct summation over the active cells (StressAtReceptor): exact; cost
//    ~ receptors x components x loads x active cells; with full-slip shear
//    (or none) the folded direct path (stress_fold.h) sums one effective
//    table instead of three (a third of the multiply-adds), equal to float
//    rounding;
//  - FFT convolution of the whole grid with each table (zero padded to
//    N >= 2n - 1, so no wrap-around; fft.h): exact; cost ~ N^2 log N per
//    transform, independent of the contact size, and only the wanted
//    components;
//  - hierarchical summation (stress_tree.h): the tables' least-squares planes
//    over cell blocks far from the receptor, to a set opening angle; cost
//    ~ receptors x components x loads x (20-250 terms), error ~ theta^2.
// `auto` picks the cheaper exact path per step from a cost model whose
// constants were measured (examples/bench_kernel.py); the choice depends on
// the inputs only, so runs stay deterministic. Pure C++: no MuJoCo types.
#ifndef MJTOUCH_STRESS_STRESS_FIELD_H_
#define MJTOUCH_STRESS_STRESS_FIELD_H_

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "common/fft.h"
#include "stress/kernel_tables.h"
#include "stress/stress_fold.h"
#include "stress/stress_tree.h"

namespace mjtouch {

enum class StressMethod { kAuto = 0, kDirect = 1, kFft = 2, kTree = 3 };
const char* StressMethodName(StressMethod m);
bool ParseStressMethod(const std::string& s, StressMethod* m);

// Spectra of the flipped lattice tables (float, split re / im), per depth and
// (load, component) that some site wants. Shared read-only like the tables.
struct KernelSpectra {
  int n = 0;      // taxel grid
  int fft_n = 0;  // padded size, >= 2 n - 1
  std::unique_ptr<Fft2D> fft;
  // [depth][load * kNumStress + comp]: re, im (fft->spectrum_size() each), or
  // empty where no site wants the component.
  std::vector<std::vector<std::vector<float>>> re, im;
  std::vector<std::array<bool, kNumStress>> want;  // per depth
  double build_seconds = 0;
};

// Components wanted at each depth (union over the sites).
std::vector<std::array<bool, kNumStress>> WantedPerDepth(const KernelTables& kt,
                                                         const std::vector<StressSite>& sites);

std::shared_ptr<const KernelSpectra> BuildKernelSpectra(const KernelTables& kt,
                                                        const std::vector<StressSite>& sites);

// Bytes that BuildKernelSpectra would allocate.
double KernelSpectraBytes(const KernelTables& kt, const std::vector<StressSite>& sites);

// Estimated seconds per evaluation of each path (one core). folded: the
// direct path is the folded one (stress_fold.h); general: the split one.
struct StressCost {
  double direct_s = 0, fft_s = 0;
};
StressCost EstimateStressCost(const KernelTables& kt, const std::vector<StressSite>& sites,
                              int active_cells, bool shear, bool folded = false,
                              bool general = false);

// Per-simulation scratch (no state that outlives a call).
struct StressScratch {
  std::vector<double> in_re, in_im, spec_re[3], spec_im[3], out_re, out_im, fft;
  TreeScratch tree;
  FoldScratch fold;
};

// How the direct path runs. uniform_slip: the shear fields are exactly
// (slip_x, slip_y) x pressure (UniformSlipShear), so the folded path
// applies; without shear it always does. fold = false: the reference direct
// sum (StressAtReceptor). threads: ThreadPool callers for the direct paths
// (any count gives the same bits). fold_legacy: the folded path with
// unaligned table loads and no rx cache (FoldScratch::fold_legacy; same bits,
// for benchmarks).
struct StressOptions {
  bool uniform_slip = false;
  double slip_x = 0, slip_y = 0;
  bool fold = true;
  int threads = 1;
  bool fold_legacy = false;
  // Any shear fields folded too (FoldedSplitStresses: the uniform-slip
  // part at slip_x, slip_y and a coarse correction) instead of the
  // reference sum: the partial-slip skin's.
  bool fold_general = false;
};
// Whether the direct path is the folded one for these tables, fields and
// options (tables that are not mirror images take the reference sum).
inline bool UsesFoldedPath(const KernelTables& kt, bool shear, const StressOptions& opt) {
  return opt.fold && (!shear || opt.uniform_slip) && kt.mirror_symmetric;
}
// Whether it is the folded path of any shear fields (FoldedSplitStresses,
// which reads the shear arrays).
inline bool UsesGeneralFoldedPath(const KernelTables& kt, bool shear, const StressOptions& opt) {
  return opt.fold && opt.fold_general && shear && !opt.uniform_slip && kt.mirror_symmetric;
}

// The path ComputeStresses takes for `method`: kAuto picks direct or FFT by
// cost (direct without spectra), kFft falls back to direct without spectra,
// kTree to kAuto without a tree. Callers that must know it first (which
// arrays the path reads) resolve it here and pass the result in.
StressMethod ResolveStressMethod(const KernelTables& kt, const KernelSpectra* spectra,
                                 const StressTree* tree, StressMethod method,
                                 const std::vector<StressSite>& sites, int active_cells, bool shear,
                                 const StressOptions& opt);
// Whether that path reads the shear arrays (all but the folded direct sum,
// which takes shear = slip x pressure).
inline bool PathReadsShear(const KernelTables& kt, StressMethod resolved, bool shear,
                           const StressOptions& opt) {
  return shear && !(resolved == StressMethod::kDirect && UsesFoldedPath(kt, shear, opt));
}

// Stress (Pa) at every site into out[site]. pressure / shear arrays: n*n,
// row-major (j * n + i); shear may be null (both or neither). runs: the
// cells with nonzero traction. kAuto picks direct or FFT by cost; kFft falls
// back to direct when spectra is null, kTree when tree is null. Returns the
// path taken.
StressMethod ComputeStresses(const KernelTables& kt, const KernelSpectra* spectra,
                             const StressTree* tree, StressMethod method,
                             const std::vector<StressSite>& sites, const ActiveRuns& runs,
                             const float* pressure, const float* shear_x, const float* shear_y,
                             StressScratch* scratch, Stress6* out,
                             const StressOptions& options = StressOptions());

// Active row runs of the cells where any traction is nonzero.
void FindActiveRuns(int n, const float* pressure, const float* shear_x, const float* shear_y,
                    ActiveRuns* runs);

}  // namespace mjtouch

#endif  // MJTOUCH_STRESS_STRESS_FIELD_H_
