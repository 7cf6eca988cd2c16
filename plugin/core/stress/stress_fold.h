// Stage 3, the folded direct path: when the shear is a uniform multiple of
// the pressure (full-slip Coulomb shear, contact/pressure.h
// UniformSlipShear: q_x = r_x p, q_y = r_y p) or absent, the stress is
//   sigma_c(site) = sum_cells (K_p,c + r_x K_x,c + r_y K_y,c) p,
// so one effective table per step and (depth, component) replaces three:
// a third of the multiply-adds and of the table reads per site. The table is
// folded band by band of kTableRowsPerBand rows (stress_fold.cc), only over
// the offsets (active cells - sites) that some site reads, and each band is
// read at once by every site of the depth while it is in L1/L2. While the
// float r_x repeats (a steady slide), K_p + r_x K_x is kept from the last
// call, so the fold reads two tables instead of three.
// The canonical sum (one sequence of float operations, whatever the ISA,
// layout or thread split): a site's cells in blocks of 8 rows on multiples
// of 8 of dy = cell row - site row (the bands), each row's products E_c * p
// accumulated by fused multiply-add (one rounding per term) in 16 float lanes
// (lane l: the cells at dx = l mod 16) over its chunks of 16 in increasing
// dx, the block's 8 row sums added in row order,
// then widened and added to 16 double lanes (blocks in increasing dy); the 16
// lanes reduced in a fixed order at the end. Zero cells are exact no-ops
// (a lane that starts at +0 never holds -0), so the chunk ranges (padding,
// rows summed together) do not change a bit. The fold is fused too: E =
// fma(r_y, K_y, fma(r_x, K_x, K_p)). The same operations run as one AVX-512
// register, two AVX2 + FMA ones or four SSE2 / NEON ones (vector lanes are
// elementwise and fma is exact: the same bits), in a copy per ISA, the
// widest the CPU has picked at run time (MJTOUCH_SUM_LANES=8 or 4 in the
// environment picks a narrower one, for tests; x86 without FMA calls fmaf,
// slow). Same result as the reference
// path (StressAtReceptor) to float rounding (tests/unit/test_stress_fold.py:
// rel. RMS <= 1e-5); the alignment and the cache do not change a bit (same
// file: against fold_legacy).
//
// Threads: each depth's sites split into `threads` ranges, each range
// folding the bands it reads; a site's sum is one fixed sequence of
// operations whatever range it is in, so the output is bit-identical for any
// thread count. Pure C++: no MuJoCo types.
#ifndef MJTOUCH_STRESS_STRESS_FOLD_H_
#define MJTOUCH_STRESS_STRESS_FOLD_H_

#include <array>
#include <vector>

#include "stress/kernel_tables.h"

namespace mjtouch {

// One site's running sums on the folded path: its 16 double lanes per
// component (d[c][l]: lane l = the cells at dx = l mod 16, stress_fold.cc).
struct alignas(64) FoldSite {
  alignas(64) double d[kNumStress][16];
  int nc = 0;                 // components summed
  int comp[kNumStress] = {};  // which
  int col = 0, off = 0;       // window column / row of pressure cell (0, 0)
  int site = 0, depth = 0;
};

// Per-simulation scratch of the folded path (no meaning between calls).
struct FoldScratch {
  std::vector<float> pressure;       // padded window, rows of `width` cells
  std::vector<int> row_lo, row_hi;   // per pressure row: its active cells
  std::vector<int> band_lo, band_hi; // per band of pressure rows: the same
  std::vector<int> sites_by_depth;   // site indices grouped by depth
  std::vector<int> depth_begin;      // ranges into sites_by_depth
  struct Window {
    int x0 = 0, y0 = 0, w = 0, h = 0;  // offsets (cell - site) of element 0; size
    int si1 = 0, sj1 = 0;              // largest site i, j at this depth
    std::array<bool, kNumStress> comps{};
  };
  std::vector<Window> window;  // per depth
  std::vector<FoldSite> sites;  // by depth, then window row of their first read
  std::vector<int> site_col;     // sites[q].col, contiguous (scanned per band)
  struct Job { int begin, end; };  // a range of `sites` (one depth)
  std::vector<Job> jobs;
  std::vector<std::vector<float>> rowbuf;  // per job: a band of folded rows per component
  std::vector<int> si0, sj0;               // per depth: smallest site i, j
  std::vector<int> fill;                   // per depth: next slot in sites_by_depth
  // The sites (and tables) the site-derived fields above were built for.
  const KernelTables* key_tables = nullptr;
  std::array<bool, kNumStress> key_components{};
  std::vector<StressSite> key_sites;
  // Kp + (+-rx) Kx (both signs of dx) and Ky per wanted (depth, component),
  // n quadrant rows each, a row in one aligned stream (stress_fold.cc
  // RxCacheHalf; h_offset: start from h_pad, -1 if none)
  // while the float rx repeats (UpdateRxCache in stress_fold.cc): the fold
  // then reads two tables, not three, each row once. A cache
  // of the inputs only: the bits do not depend on it.
  std::vector<float> h;
  std::vector<long> h_offset;
  const KernelTables* h_tables = nullptr;
  std::array<bool, kNumStress> h_components{};
  float h_rx = 0;
  int h_calls = 0;
  bool h_valid = false;
  long h_pad = 0;  // h's cells from index h_pad (its first 64-byte boundary when built)
  double seconds = 0;  // the last call's fold + sums (diagnostics)
  // The table loads unaligned (every one splits a cache line) and no rx
  // cache (the same bits): for the benchmark's ratio and the tests.
  bool fold_legacy = false;
};

// Stress (Pa) at every site into out[site] (components a site does not want
// are zero). Needs kt.mirror_symmetric (every laterally isotropic substrate). shear: whether the tractions include the uniform-slip shear
// (slip_x, slip_y: shear / pressure); false: pressure only. threads: callers
// of ThreadPool::Shared(); any value gives the same bits.
void FoldedDirectStresses(const KernelTables& kt, const std::vector<StressSite>& sites,
                          const ActiveRuns& runs, const float* pressure, bool shear,
                          double slip_x, double slip_y, int threads, FoldScratch* w,
                          Stress6* out);

// The reference direct sum (StressAtReceptor per site and component), with
// the sites split over threads the same way (bit-identical for any count).
void ReferenceDirectStresses(const KernelTables& kt, const std::vector<StressSite>& sites,
                             const ActiveRuns& runs, const float* pressure,
                             const float* shear_x, const float* shear_y, int threads,
                             Stress6* out);

// Seconds per evaluation of the folded path (one core): the fold of the
// window and the sums; fitted by examples/bench_kernel.py.
double EstimateFoldedSeconds(const KernelTables& kt, const std::vector<StressSite>& sites,
                             int active_cells);

}  // namespace mjtouch

#endif  // MJTOUCH_STRESS_STRESS_FOLD_H_
