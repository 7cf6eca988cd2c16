// Stage 3, folded direct path: with a uniform-slip shear (q = r p, contact/
// pressure.h UniformSlipShear) or none, the stress is sum_cells (K_p + r_x K_x
// + r_y K_y) p, so one folded table per (depth, component) replaces three.
// Every site's sum is one fixed sequence of float operations
// (stress_fold_kernels.cc), so the output is bit-identical on every ISA and
// for any thread count.
#ifndef MJTOUCH_STRESS_STRESS_FOLD_H_
#define MJTOUCH_STRESS_STRESS_FOLD_H_

#include <array>
#include <cstdint>
#include <vector>

#include "stress/kernel_tables.h"

namespace mjtouch {

// One site's running sums on the folded path: its 16 double lanes per
// component (d[c][l]: lane l = the cells at dx = l mod 16, stress_fold_kernels.cc).
struct alignas(64) FoldSite {
  alignas(64) double d[kNumStress][16];
  int nc = 0;                 // components summed
  int comp[kNumStress] = {};  // which
  int col = 0, off = 0;       // window column / row of pressure cell (0, 0)
  int site = 0, depth = 0;
};

// Per-simulation scratch of the folded path (no meaning between calls).
struct FoldScratch {
  std::vector<float> pressure;        // padded window, rows of `width` cells
  std::vector<int> row_lo, row_hi;    // per pressure row: its active cells
  std::vector<int> band_lo, band_hi;  // per band of pressure rows: the same
  std::vector<int> sites_by_depth;    // site indices grouped by depth
  std::vector<int> depth_begin;       // ranges into sites_by_depth
  struct Window {
    int x0 = 0, y0 = 0, w = 0, h = 0;  // offsets (cell - site) of element 0; size
    int si1 = 0, sj1 = 0;              // largest site i, j at this depth
    std::array<bool, kNumStress> comps{};
  };
  std::vector<Window> window;   // per depth
  std::vector<FoldSite> sites;  // by depth, then window row of their first read
  std::vector<int> site_col;    // sites[q].col, contiguous (scanned per band)
  struct Job {
    int begin, end;
  };  // a range of `sites` (one depth)
  std::vector<Job> jobs;
  std::vector<std::vector<float>> rowbuf;  // per job: a band of folded rows per component
  std::vector<int> si0, sj0;               // per depth: smallest site i, j
  std::vector<int> fill;                   // per depth: next slot in sites_by_depth
  // The sites (and tables) the site-derived fields above were built for.
  const KernelTables* key_tables = nullptr;
  std::array<bool, kNumStress> key_components{};
  std::vector<StressSite> key_sites;
  // Kp + (+-rx) Kx (both signs of dx) and Ky per wanted (depth, component),
  // n quadrant rows each, a row in one aligned stream (stress_fold_internal.h
  // RxCacheHalf; h_offset: start from h_pad, -1 if none)
  // while the float rx repeats (UpdateRxCache, stress_fold_plan.cc): the fold
  // then reads two tables, not three, each row once. A cache
  // of the inputs only: the bits do not depend on it.
  std::vector<float> h;
  std::vector<long> h_offset;
  const KernelTables* h_tables = nullptr;
  std::array<bool, kNumStress> h_components{};
  float h_rx = 0;
  int h_calls = 0;
  bool h_valid = false;
  long h_pad = 0;      // h's cells from index h_pad (its first 64-byte boundary when built)
  double seconds = 0;  // the last call's fold + sums (diagnostics)
  // The table loads unaligned (every one splits a cache line) and no rx
  // cache (the same bits): for the benchmark's ratio and the tests.
  bool fold_legacy = false;
  // FoldedSplitStresses: the shear tables by lattice phase (CoarseShearTables)
  // and the coarse correction's node fields.
  std::vector<uint16_t> coarse_tables;  // bfloat16
  std::vector<long> coarse_offset;      // per (depth, load x / y, component): -1 if not wanted
  const KernelTables* coarse_key = nullptr;
  std::vector<std::array<bool, kNumStress>> coarse_want;
  std::vector<float> node_x, node_y;  // rows of node_stride, zero padded
  std::vector<double> node_sum_x, node_sum_y, row_nodes_x, row_nodes_y;
  int coarse_cells = 1;  // the lattice's spacing s, cells
};

// Stress (Pa) at every site into out[site] (components a site does not want
// are zero). Needs kt.mirror_symmetric (every laterally isotropic substrate). shear: whether the
// tractions include the uniform-slip shear (slip_x, slip_y: shear / pressure); false: pressure
// only. threads: callers of ThreadPool::Shared(); any value gives the same bits.
void FoldedDirectStresses(const KernelTables& kt, const std::vector<StressSite>& sites,
                          const ActiveRuns& runs, const float* pressure, bool shear, double slip_x,
                          double slip_y, int threads, FoldScratch* w, Stress6* out);

// The same split into the full-slip part and a correction: the folded sum
// of the pressure at the ratios (slip_x, slip_y) (FoldedDirectStresses'),
// plus the stress of the rest dq = q - slip p, which carries no net force
// (the tractions sum to the friction force either way), from dq moved onto
// the nodes of a lattice s cells apart by quadratic Lagrange weights
// (separable, on each cell's nearest node and its two neighbours per axis),
// which keep each cell's force and first and second moments: the error is
// the kernels' interpolation error over the node spacing, third order. The
// spacing s pitch is at most kCoarseSpacingPerDepth of the shallowest
// site's depth (s = 1: the exact sum; s in [1, kMaxCoarseCells]):
// examples/bench_partial_slip.py reports the error against the exact sums.
constexpr double kCoarseSpacingPerDepth = 0.55;
constexpr int kMaxCoarseCells = 16;
void FoldedSplitStresses(const KernelTables& kt, const std::vector<StressSite>& sites,
                         const ActiveRuns& runs, const float* pressure, const float* shear_x,
                         const float* shear_y, double slip_x, double slip_y, int threads,
                         FoldScratch* w, Stress6* out);

// The reference direct sum (StressAtReceptor per site and component), with
// the sites split over threads the same way (bit-identical for any count).
void ReferenceDirectStresses(const KernelTables& kt, const std::vector<StressSite>& sites,
                             const ActiveRuns& runs, const float* pressure, const float* shear_x,
                             const float* shear_y, int threads, Stress6* out);

// Seconds per evaluation of the folded path (one core): the fold of the
// window and the sums; fitted by examples/bench_kernel.py.
double EstimateFoldedSeconds(const KernelTables& kt, const std::vector<StressSite>& sites,
                             int active_cells);

}  // namespace mjtouch

#endif  // MJTOUCH_STRESS_STRESS_FOLD_H_
