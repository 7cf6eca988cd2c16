#include "stress/stress_fold.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "common/thread_pool.h"

// The 8-lane helpers below are always inlined into the target_clones
// functions, so their by-value vector ABI never applies.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace mjtouch {
namespace {

constexpr int kLanes = 8;           // cells per chunk (one AVX2 vector)
constexpr int kFoldRowsPerChunk = 16;
constexpr int kSitesPerChunk = 8;
// Float lanes are widened to double every this many rows (a site's sum has
// ~10^3-10^4 terms; float over a few rows keeps the error ~1e-7).
constexpr int kRowsPerFlush = 8;
// Cost model of the folded path (one core; examples/bench_kernel.py
// --calibrate fits them): per site x component x active cell, and per folded
// table cell. Measured on the 2-core development machine under load, scaled
// by the reference path's fixed / measured constant in the same run (0.65).
constexpr double kFoldedSecondsPerMac = 0.05e-9;
constexpr double kFoldSecondsPerCell = 0.22e-9;

typedef float v8f __attribute__((vector_size(32)));
typedef float v4f __attribute__((vector_size(16)));
typedef double v4d __attribute__((vector_size(32)));

inline __attribute__((always_inline)) v8f Load(const float* p) {
  v8f v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}

// Widen a float vector's halves into two double accumulators.
inline __attribute__((always_inline)) void Flush(v8f a, v4d* d) {
  const v4f lo = {a[0], a[1], a[2], a[3]};
  const v4f hi = {a[4], a[5], a[6], a[7]};
  d[0] += __builtin_convertvector(lo, v4d);
  d[1] += __builtin_convertvector(hi, v4d);
}

// Rows [r0, r1) of one site's NC components: E_c * p summed in float lanes
// (U interleaved accumulators per component, so one-component sites are not
// bound by the add latency), then widened into the site's double sums d.
// The order of every operation is fixed by the inputs.
template <int NC, int U>
inline __attribute__((always_inline)) void SumRows(const float* const* E, size_t base, int ew,
                                                   const float* P, int pw, const int* lo,
                                                   const int* hi, int r0, int r1, v4d* d) {
  v8f acc[U][NC];
  for (int u = 0; u < U; ++u)
    for (int c = 0; c < NC; ++c) acc[u][c] = v8f{0, 0, 0, 0, 0, 0, 0, 0};
  for (int r = r0; r < r1; ++r) {
    const int x1 = hi[r];
    const float* prow = P + static_cast<size_t>(r) * pw;
    const float* erow[NC];
    for (int c = 0; c < NC; ++c) erow[c] = E[c] + base + static_cast<size_t>(r) * ew;
    int x = lo[r];
    for (; x + U * kLanes <= x1; x += U * kLanes)
      for (int u = 0; u < U; ++u) {
        const v8f p = Load(prow + x + u * kLanes);
        for (int c = 0; c < NC; ++c) acc[u][c] += Load(erow[c] + x + u * kLanes) * p;
      }
    for (; x < x1; x += kLanes) {
      const v8f p = Load(prow + x);
      for (int c = 0; c < NC; ++c) acc[0][c] += Load(erow[c] + x) * p;
    }
  }
  for (int c = 0; c < NC; ++c) {
    v8f a = acc[0][c];
    for (int u = 1; u < U; ++u) a += acc[u][c];
    Flush(a, d + 2 * c);
  }
}

// One chunk's sites (at most kSitesPerChunk), band by band of kRowsPerFlush
// pressure rows, so the table rows a band needs are reused from L1 by every
// site of the chunk. Each site's sum is the same sequence of operations as
// summing it alone.
struct SiteSum {
  int nc = 0;
  const float* E[kNumStress];
  size_t base = 0;
  v4d d[2 * kNumStress];
};

__attribute__((target_clones("avx2", "default")))
void SumChunk(SiteSum* sites, int count, int ew, const float* P, int pw, const int* lo,
              const int* hi, int rows) {
  for (int q = 0; q < count; ++q)
    for (auto& v : sites[q].d) v = v4d{0, 0, 0, 0};
  for (int r0 = 0; r0 < rows; r0 += kRowsPerFlush) {
    const int r1 = std::min(rows, r0 + kRowsPerFlush);
    for (int q = 0; q < count; ++q) {
      SiteSum& s = sites[q];
      switch (s.nc) {
        case 0: break;
        case 1: SumRows<1, 4>(s.E, s.base, ew, P, pw, lo, hi, r0, r1, s.d); break;
        case 2: SumRows<2, 2>(s.E, s.base, ew, P, pw, lo, hi, r0, r1, s.d); break;
        case 3: SumRows<3, 2>(s.E, s.base, ew, P, pw, lo, hi, r0, r1, s.d); break;
        case 4: SumRows<4, 1>(s.E, s.base, ew, P, pw, lo, hi, r0, r1, s.d); break;
        case 5: SumRows<5, 1>(s.E, s.base, ew, P, pw, lo, hi, r0, r1, s.d); break;
        default: SumRows<6, 1>(s.E, s.base, ew, P, pw, lo, hi, r0, r1, s.d); break;
      }
    }
  }
}

// e[x] = (kp[x] + rx kx[x]) + ry ky[x] (float), or kp[x] without shear.
__attribute__((target_clones("avx2", "default")))
void FoldRow(const float* kp, const float* kx, const float* ky, float rx, float ry, bool shear,
             int len, float* e) {
  if (shear) {
    for (int x = 0; x < len; ++x) e[x] = (kp[x] + rx * kx[x]) + ry * ky[x];
  } else {
    std::memcpy(e, kp, sizeof(float) * len);
  }
}

// The same from a mirrored source, read backwards (k[-x]), times sign
// (+-1, exact): a table row at negative offsets from its row at positive ones.
__attribute__((target_clones("avx2", "default")))
void FoldRowReversed(const float* kp, const float* kx, const float* ky, float rx, float ry,
                     float sign, bool shear, int len, float* e) {
  if (shear) {
    for (int x = 0; x < len; ++x) e[x] = sign * ((kp[-x] + rx * kx[-x]) + ry * ky[-x]);
  } else {
    for (int x = 0; x < len; ++x) e[x] = sign * kp[-x];
  }
}

// One row of a folded window (offset dy, columns dx = x0 .. x0 + w - 1) from
// the tables' rows at |dy| and columns |dx| only (KernelTables::
// mirror_symmetric): the signs of the reflections folded into the ratios,
// E = sp (Kp + (sp sx rx) Kx + (sp sy ry) Ky), exactly the value the full
// tables give when they are mirror images.
void FoldMirroredRow(const KernelTables& kt, int d, StressComponent comp, int dy, int x0, int w,
                     float rx, float ry, bool shear, float* e) {
  const int n = kt.n, L = 2 * n - 1;
  std::fill(e, e + w, 0.0f);
  const int ady = dy < 0 ? -dy : dy;
  if (ady > n - 1) return;
  const size_t row = static_cast<size_t>(ady + n - 1) * L + (n - 1);  // offset (0, |dy|)
  const float* Kp = kt.At(d, kLoadPressure, comp) + row;
  const float* Kx = kt.At(d, kLoadShearX, comp) + row;
  const float* Ky = kt.At(d, kLoadShearY, comp) + row;
  for (int side = 0; side < 2; ++side) {  // dx >= 0, then dx < 0
    const int lo = side == 0 ? std::max(0, x0) : std::max(-(n - 1), x0);
    const int hi = side == 0 ? std::min(n - 1, x0 + w - 1) : std::min(-1, x0 + w - 1);
    if (lo > hi) continue;
    float sp = 1, sx = 1, sy = 1;
    if (side == 1) {
      sp *= MirrorSign(0, kLoadPressure, comp);
      sx *= MirrorSign(0, kLoadShearX, comp);
      sy *= MirrorSign(0, kLoadShearY, comp);
    }
    if (dy < 0) {
      sp *= MirrorSign(1, kLoadPressure, comp);
      sx *= MirrorSign(1, kLoadShearX, comp);
      sy *= MirrorSign(1, kLoadShearY, comp);
    }
    const float a = sp * sx * rx, b = sp * sy * ry;
    if (side == 0) {
      float* out = e + (lo - x0);
      FoldRow(Kp + lo, Kx + lo, Ky + lo, a, b, shear, hi - lo + 1, out);
      if (sp < 0)
        for (int x = 0; x <= hi - lo; ++x) out[x] = -out[x];
    } else {
      // e at dx = lo .. hi reads the positive-offset row at -lo .. -hi.
      FoldRowReversed(Kp - lo, Kx - lo, Ky - lo, a, b, sp, shear, hi - lo + 1, e + (lo - x0));
    }
  }
}

int CountWanted(const std::array<bool, kNumStress>& w) {
  int c = 0;
  for (bool b : w) c += b;
  return c;
}

}  // namespace

void FoldedDirectStresses(const KernelTables& kt, const std::vector<StressSite>& sites,
                          const ActiveRuns& runs, const float* pressure, bool shear,
                          double slip_x, double slip_y, int threads, FoldScratch* w,
                          Stress6* out) {
  for (size_t s = 0; s < sites.size(); ++s) out[s].fill(0.0);
  if (runs.row.empty() || sites.empty()) return;
  const int n = kt.n;
  const int D = static_cast<int>(kt.depths_m.size());
  // Active box, its columns padded to whole chunks.
  int i0 = n, i1 = -1, j0 = runs.row.front(), j1 = runs.row.back();
  for (size_t r = 0; r < runs.row.size(); ++r) {
    i0 = std::min(i0, runs.begin[r]);
    i1 = std::max(i1, runs.end[r] - 1);
    j0 = std::min(j0, runs.row[r]);
    j1 = std::max(j1, runs.row[r]);
  }
  const int rows = j1 - j0 + 1;
  const int pw = (i1 - i0 + kLanes) / kLanes * kLanes;
  w->pressure.assign(static_cast<size_t>(rows) * pw, 0.0f);
  w->row_lo.assign(rows, pw);
  w->row_hi.assign(rows, 0);
  for (size_t r = 0; r < runs.row.size(); ++r) {
    const int y = runs.row[r] - j0;
    const int b = runs.begin[r] - i0, e = runs.end[r] - i0;
    std::copy(pressure + static_cast<size_t>(runs.row[r]) * n + runs.begin[r],
              pressure + static_cast<size_t>(runs.row[r]) * n + runs.end[r],
              w->pressure.begin() + static_cast<size_t>(y) * pw + b);
    w->row_lo[y] = std::min(w->row_lo[y], b / kLanes * kLanes);
    w->row_hi[y] = std::max(w->row_hi[y], (e + kLanes - 1) / kLanes * kLanes);
  }
  // Sites grouped by depth, and each depth's table window.
  w->window.assign(D, FoldScratch::Window{});
  w->depth_begin.assign(D + 1, 0);
  std::vector<int> si0(D, n), sj0(D, n);
  for (auto& win : w->window) win.si1 = win.sj1 = -1;
  for (const StressSite& s : sites) {
    auto& win = w->window[s.depth_index];
    w->depth_begin[s.depth_index + 1]++;
    si0[s.depth_index] = std::min(si0[s.depth_index], s.i);
    sj0[s.depth_index] = std::min(sj0[s.depth_index], s.j);
    win.si1 = std::max(win.si1, s.i);
    win.sj1 = std::max(win.sj1, s.j);
    for (int c = 0; c < kNumStress; ++c) win.comps[c] = win.comps[c] || (s.want[c] && kt.components[c]);
  }
  for (int d = 0; d < D; ++d) w->depth_begin[d + 1] += w->depth_begin[d];
  w->sites_by_depth.resize(sites.size());
  {
    std::vector<int> fill(w->depth_begin.begin(), w->depth_begin.end() - 1);
    for (size_t s = 0; s < sites.size(); ++s)
      w->sites_by_depth[fill[sites[s].depth_index]++] = static_cast<int>(s);
    // Each depth's sites by row, then column: a chunk's sites read nearby
    // table rows (fixed by the sites alone, so the same order every step).
    for (int d = 0; d < D; ++d)
      std::sort(w->sites_by_depth.begin() + w->depth_begin[d],
                w->sites_by_depth.begin() + w->depth_begin[d + 1], [&](int a, int b) {
                  const StressSite &sa = sites[a], &sb = sites[b];
                  return sa.j != sb.j ? sa.j < sb.j : (sa.i != sb.i ? sa.i < sb.i : a < b);
                });
  }
  w->eff.resize(static_cast<size_t>(D) * kNumStress);
  // Fold jobs: blocks of |dy| (the rows dy and -dy share their source rows,
  // read once).
  struct FoldJob { int d, c, y0, y1; };
  std::vector<FoldJob> folds;
  for (int d = 0; d < D; ++d) {
    auto& win = w->window[d];
    if (win.si1 < 0) continue;
    win.x0 = i0 - win.si1;
    win.y0 = j0 - win.sj1;
    win.w = pw + win.si1 - si0[d];
    win.h = rows + win.sj1 - sj0[d];
    for (int c = 0; c < kNumStress; ++c) {
      if (!win.comps[c]) continue;
      w->eff[d * kNumStress + c].resize(static_cast<size_t>(win.w) * win.h);
      const int end = std::max(std::abs(win.y0), std::abs(win.y0 + win.h - 1)) + 1;
      for (int y = 0; y < end; y += kFoldRowsPerChunk)
        folds.push_back({d, c, y, std::min(end, y + kFoldRowsPerChunk)});
    }
  }
  const float rx = static_cast<float>(slip_x), ry = static_cast<float>(slip_y);
  ThreadPool& pool = ThreadPool::Shared();
  const auto t0 = std::chrono::steady_clock::now();
  pool.Run(static_cast<int>(folds.size()), threads, [&](int k) {
    const FoldJob& f = folds[k];
    const auto& win = w->window[f.d];
    const auto comp = static_cast<StressComponent>(f.c);
    float* E = w->eff[f.d * kNumStress + f.c].data();
    for (int a = f.y0; a < f.y1; ++a)
      for (int sign = 0; sign < (a == 0 ? 1 : 2); ++sign) {
        const int dy = sign ? -a : a;
        const int y = dy - win.y0;
        if (y < 0 || y >= win.h) continue;
        FoldMirroredRow(kt, f.d, comp, dy, win.x0, win.w, rx, ry, shear,
                        E + static_cast<size_t>(y) * win.w);
      }
  });
  const auto t1 = std::chrono::steady_clock::now();
  // Sums: blocks of sites of one depth.
  struct SumJob { int d, s0, s1; };
  std::vector<SumJob> sums;
  for (int d = 0; d < D; ++d)
    for (int s = w->depth_begin[d]; s < w->depth_begin[d + 1]; s += kSitesPerChunk)
      sums.push_back({d, s, std::min(w->depth_begin[d + 1], s + kSitesPerChunk)});
  pool.Run(static_cast<int>(sums.size()), threads, [&](int k) {
    const SumJob& job = sums[k];
    const auto& win = w->window[job.d];
    SiteSum chunk[kSitesPerChunk];
    int comp[kSitesPerChunk][kNumStress];
    int count = 0;
    for (int q = job.s0; q < job.s1; ++q, ++count) {
      const StressSite& site = sites[w->sites_by_depth[q]];
      SiteSum& ss = chunk[count];
      ss.nc = 0;
      for (int c = 0; c < kNumStress; ++c)
        if (site.want[c] && win.comps[c]) {
          ss.E[ss.nc] = w->eff[job.d * kNumStress + c].data();
          comp[count][ss.nc++] = c;
        }
      // Window element of (row j0, column i0) for this site.
      ss.base = static_cast<size_t>(win.sj1 - site.j) * win.w + (win.si1 - site.i);
    }
    SumChunk(chunk, count, win.w, w->pressure.data(), pw, w->row_lo.data(), w->row_hi.data(),
             rows);
    for (int q = 0; q < count; ++q) {
      const int si = w->sites_by_depth[job.s0 + q];
      for (int c = 0; c < chunk[q].nc; ++c) {
        const v4d s = chunk[q].d[2 * c] + chunk[q].d[2 * c + 1];
        out[si][comp[q][c]] = (s[0] + s[1]) + (s[2] + s[3]);
      }
    }
  });
  const auto t2 = std::chrono::steady_clock::now();
  w->fold_seconds = std::chrono::duration<double>(t1 - t0).count();
  w->sum_seconds = std::chrono::duration<double>(t2 - t1).count();
}

void ReferenceDirectStresses(const KernelTables& kt, const std::vector<StressSite>& sites,
                             const ActiveRuns& runs, const float* pressure,
                             const float* shear_x, const float* shear_y, int threads,
                             Stress6* out) {
  for (size_t s = 0; s < sites.size(); ++s) out[s].fill(0.0);
  // Component-major, depth by depth: the three tables of one (depth,
  // component), ~0.8 MB at n = 128, stay in cache while its sites read their
  // windows (site-major order streamed all 18 tables per site: 2-3x slower).
  struct Job { int d, c, s0, s1; };
  std::vector<Job> jobs;
  std::vector<int> order;
  for (size_t d = 0; d < kt.depths_m.size(); ++d)
    for (int c = 0; c < kNumStress; ++c) {
      if (!kt.components[c]) continue;
      const int first = static_cast<int>(order.size());
      for (size_t s = 0; s < sites.size(); ++s)
        if (sites[s].depth_index == static_cast<int>(d) && sites[s].want[c])
          order.push_back(static_cast<int>(s));
      const int last = static_cast<int>(order.size());
      for (int s = first; s < last; s += kSitesPerChunk)
        jobs.push_back({static_cast<int>(d), c, s, std::min(last, s + kSitesPerChunk)});
    }
  ThreadPool::Shared().Run(static_cast<int>(jobs.size()), threads, [&](int k) {
    const Job& job = jobs[k];
    std::array<bool, kNumStress> one{};
    one[job.c] = true;
    Stress6 tmp;
    for (int q = job.s0; q < job.s1; ++q) {
      const StressSite& site = sites[order[q]];
      StressAtReceptor(kt, job.d, site.i, site.j, runs, pressure, shear_x, shear_y, one, &tmp);
      out[order[q]][job.c] = tmp[job.c];
    }
  });
}

double EstimateFoldedSeconds(const KernelTables& kt, const std::vector<StressSite>& sites,
                             int active_cells) {
  double macs = 0;
  int si0 = kt.n, si1 = -1, sj0 = kt.n, sj1 = -1;
  std::vector<std::array<bool, kNumStress>> want(kt.depths_m.size());
  for (const StressSite& s : sites) {
    macs += CountWanted(s.want);
    si0 = std::min(si0, s.i);
    si1 = std::max(si1, s.i);
    sj0 = std::min(sj0, s.j);
    sj1 = std::max(sj1, s.j);
    for (int c = 0; c < kNumStress; ++c)
      want[s.depth_index][c] = want[s.depth_index][c] || (s.want[c] && kt.components[c]);
  }
  if (si1 < 0) return 0.0;
  int tables = 0;
  for (const auto& w : want) tables += CountWanted(w);
  // The contact's box taken as a square of its active cells.
  const double side = std::sqrt(static_cast<double>(active_cells)) + kLanes;
  const double window = (side + si1 - si0) * (side + sj1 - sj0);
  return kFoldedSecondsPerMac * macs * active_cells + kFoldSecondsPerCell * tables * window;
}

}  // namespace mjtouch
