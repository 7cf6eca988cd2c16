// Internal to the folded direct path (stress_fold*.cc): the shared
// constants, the per-ISA kernels (stress_fold_kernels.cc) and the planning
// steps (stress_fold_plan.cc) the driver (stress_fold.cc) calls.
#ifndef MJTOUCH_STRESS_STRESS_FOLD_INTERNAL_H_
#define MJTOUCH_STRESS_STRESS_FOLD_INTERNAL_H_

#include <cstddef>
#include <cstdint>
#include <vector>

#include "stress/stress_fold.h"

namespace mjtouch {
namespace fold_detail {

constexpr int kSumLanes = 16;   // lanes of the canonical sum (stress_fold_kernels.cc)
constexpr int kFoldLanes = 16;  // cells per fold chunk (one AVX-512 vector)
constexpr int kSitesPerChunk = 8;
// Folded table rows per band: folded together, then read by every site; also
// the rows whose float sums are widened to double at once (a site's sum has
// ~10^3-10^4 terms; float over a few rows keeps the error ~1e-7).
constexpr int kTableRowsPerBand = 8;

// FoldScratch::h's layout, per wanted (depth, component) and quadrant row
// |dy| = 0 .. n - 1, from a 64-byte boundary: h = kp + (sp sx rx) kx at dx =
// -half .. half - 1 (half = RxCacheHalf(n); the quadrant of +rx at dx >= 0,
// of -rx at dx < 0: KernelTables MirrorSign, a shear x odd under x and even
// under y), then ky at |dx| = 0 .. half + 15. A chunk of 16 at dx = 0 mod 16
// reads h forwards and aligned on both sides, and ky so for dx >= 0; for dx
// < 0 it reads ky's cells |dx| backwards from the lines the dx >= 0 side has
// just brought in: a row's three tables read once (fewer lines per step
// than both sides of ky stored, which the fold is bound by when the step's
// other stages have evicted them). Cells beyond the tables (|dx| > n - 1)
// hold +0, so they fold to +-0 (an exact no-op in the sums).
inline int RxCacheHalf(int n) { return (n + kFoldLanes - 1) / kFoldLanes * kFoldLanes; }
inline size_t RxCacheStride(int n) { return static_cast<size_t>(3) * RxCacheHalf(n) + kFoldLanes; }

// The first 64-byte aligned float at or after p (buffers allocate 16 more).
inline float* AlignUp64(float* p) {
  const uintptr_t a = reinterpret_cast<uintptr_t>(p);
  return p + ((64 - a % 64) % 64) / sizeof(float);
}

// Kernels, in a copy per ISA (common/simd.h MJTOUCH_ISA_COPIES).
// The sums of sites [first, last) over one band of folded table rows
// (window rows [T0, T0 + kTableRowsPerBand)).
void SumBand(FoldSite* sites, int first, int last, const float* const* ebuf, int ew, int T0,
             const float* P, int ps, const int* rlo, const int* rhi, int x0);
// Folded rows dy0 .. dy0 + rows - 1 (rows ew apart) at dx = x0 .. x0 + w - 1
// from the rx cache h of one (depth, component).
void FoldCachedRows(const float* h, int n, StressComponent comp, int dy0, int rows, int x0, int w,
                    float ry, float* e, int ew);
// The same rows folded from the tables (mirror symmetric) at ratios rx, ry;
// without shear, the table of load `single` alone.
void FoldMirroredRows(const KernelTables& kt, int d, StressComponent comp, int dy0, int rows,
                      int x0, int w, float rx, float ry, bool shear, SurfaceLoad single, float* e,
                      int ew);

// The coarse correction's sums of one site's nc components
// (FoldedSplitStresses): over `rows` node rows, the x and y shear tables'
// rows (tx[c], ty[c] in bfloat16, tstride apart) against the node fields' (vstride
// apart) at `cols` columns, a multiple of 16 (the tables readable 15 floats
// beyond), into result[c].
void CoarseDots(const uint16_t* const* tx, const uint16_t* const* ty, int nc, long tstride,
                const float* vx, const float* vy, int vstride, int rows, int cols, double* result);

// Planning (stress_fold_plan.cc).
// FoldScratch::h for float rx: built on the second consecutive call with the
// same tables and rx, dropped when rx changes (h_valid says whether it holds).
void UpdateRxCache(const KernelTables& kt, float rx, FoldScratch* w);
// The sites grouped by depth and window row, each depth's window and
// components, and the sites' states in that order (FoldScratch).
void SortSites(const KernelTables& kt, const std::vector<StressSite>& sites, FoldScratch* w);

}  // namespace fold_detail
}  // namespace mjtouch

#endif  // MJTOUCH_STRESS_STRESS_FOLD_INTERNAL_H_
