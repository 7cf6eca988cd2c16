// The folded path's planning (stress_fold.h): the sites sorted into
// per-depth windows (SortSites), the rx cache (UpdateRxCache) and the cost
// model of the path (EstimateFoldedSeconds).
#include <algorithm>
#include <cmath>
#include <cstring>

#include "common/exact_fma.h"
#include "stress/stress_fold_internal.h"

namespace mjtouch {
namespace fold_detail {

// FoldScratch::h: kp + (+-rx) kx over each wanted (depth, component)'s
// quadrant, built on the second consecutive call with the same tables and
// float rx (a steady slide: MuJoCo's F_t / F_n at the friction cone rounds
// to the same float step after step), dropped when rx changes. Only speed
// depends on it: FoldCachedRows gives FoldMirroredRows' bits.
void UpdateRxCache(const KernelTables& kt, float rx, FoldScratch* w) {
  if (w->h_tables != &kt || w->h_components != kt.components || w->h_calls == 0 ||
      std::memcmp(&w->h_rx, &rx, sizeof(rx)) != 0) {
    w->h_tables = &kt;
    w->h_components = kt.components;
    w->h_rx = rx;
    w->h_calls = 1;
    w->h_valid = false;
    return;
  }
  // A copied scratch (mj_copyData) holds the cache at another alignment:
  // laid out again (the layout is by index from h_pad, so it reads right
  // either way; only the loads' alignment is lost).
  if (w->h_valid && AlignUp64(w->h.data()) != w->h.data() + w->h_pad) w->h_valid = false;
  if (w->h_valid || ++w->h_calls < 2) return;
  const int n = kt.n, L = 2 * n - 1;
  const int D = static_cast<int>(kt.depths_m.size());
  w->h_offset.assign(static_cast<size_t>(D) * kNumStress, -1);
  const size_t hs = RxCacheStride(n);
  const int half = RxCacheHalf(n);
  size_t size = 0;
  for (int d = 0; d < D; ++d)
    for (int c = 0; c < kNumStress; ++c)
      if (w->window[d].comps[c]) {
        w->h_offset[d * kNumStress + c] = static_cast<long>(size);
        size += hs * n;
      }
  w->h.assign(size + 16, 0.0f);
  w->h_pad = AlignUp64(w->h.data()) - w->h.data();
  float* const h0 = w->h.data() + w->h_pad;
  for (int d = 0; d < D; ++d)
    for (int c = 0; c < kNumStress; ++c) {
      const long off = w->h_offset[d * kNumStress + c];
      if (off < 0) continue;
      const auto comp = static_cast<StressComponent>(c);
      for (int y = 0; y < n; ++y) {
        const size_t row = static_cast<size_t>(y + n - 1) * L + (n - 1);
        const float* Kp = kt.At(d, kLoadPressure, comp) + row;
        const float* Kx = kt.At(d, kLoadShearX, comp) + row;
        const float* Ky = kt.At(d, kLoadShearY, comp) + row;
        float* Hy = h0 + off + y * hs;
        for (int dx = -(n - 1); dx < n; ++dx) {  // the rest stays +0
          const int x = dx < 0 ? -dx : dx;
          const float a = dx < 0 ? -rx : rx;
          const int i = dx + half;
          Hy[i] = FmaFromDouble(a, Kx[x], Kp[x]);  // the fold's fma (FoldRowCells)
          if (dx >= 0) Hy[2 * half + x] = Ky[x];
        }
      }
    }
  w->h_valid = true;
}

int CountWanted(const std::array<bool, kNumStress>& w) {
  int c = 0;
  for (bool b : w) c += b;
  return c;
}

// Sites grouped by depth (each by the window row it starts reading at, row
// j descending, then column), each depth's largest / smallest site i, j and
// components, and the sites' states in that order.
void SortSites(const KernelTables& kt, const std::vector<StressSite>& sites, FoldScratch* w) {
  const int n = kt.n;
  const int D = static_cast<int>(kt.depths_m.size());
  w->window.assign(D, FoldScratch::Window{});
  w->depth_begin.assign(D + 1, 0);
  w->si0.assign(D, n);
  w->sj0.assign(D, n);
  std::vector<int>& si0 = w->si0;
  std::vector<int>& sj0 = w->sj0;
  for (auto& win : w->window) win.si1 = win.sj1 = -1;
  for (const StressSite& s : sites) {
    auto& win = w->window[s.depth_index];
    w->depth_begin[s.depth_index + 1]++;
    si0[s.depth_index] = std::min(si0[s.depth_index], s.i);
    sj0[s.depth_index] = std::min(sj0[s.depth_index], s.j);
    win.si1 = std::max(win.si1, s.i);
    win.sj1 = std::max(win.sj1, s.j);
    for (int c = 0; c < kNumStress; ++c)
      win.comps[c] = win.comps[c] || (s.want[c] && kt.components[c]);
  }
  for (int d = 0; d < D; ++d) w->depth_begin[d + 1] += w->depth_begin[d];
  w->sites_by_depth.resize(sites.size());
  {
    std::vector<int>& fill = w->fill;
    fill.assign(w->depth_begin.begin(), w->depth_begin.end() - 1);
    for (size_t s = 0; s < sites.size(); ++s)
      w->sites_by_depth[fill[sites[s].depth_index]++] = static_cast<int>(s);
    // Each depth's sites by the window row they start at (row j, descending),
    // then column (fixed by the sites alone, so the same order every step).
    for (int d = 0; d < D; ++d)
      std::sort(w->sites_by_depth.begin() + w->depth_begin[d],
                w->sites_by_depth.begin() + w->depth_begin[d + 1], [&](int a, int b) {
                  const StressSite &sa = sites[a], &sb = sites[b];
                  return sa.j != sb.j ? sa.j > sb.j : (sa.i != sb.i ? sa.i < sb.i : a < b);
                });
  }
  // Each depth's table window, and its sites' states in the order of the
  // window row they start reading at (off), so the sites reading a row are
  // a contiguous range.
  w->sites.clear();
  for (int d = 0; d < D; ++d) {
    auto& win = w->window[d];
    if (win.si1 < 0) continue;
    for (int q = w->depth_begin[d]; q < w->depth_begin[d + 1]; ++q) {
      const StressSite& site = sites[w->sites_by_depth[q]];
      FoldSite fs;
      fs.nc = 0;
      for (int c = 0; c < kNumStress; ++c)
        if (site.want[c] && win.comps[c]) fs.comp[fs.nc++] = c;
      if (fs.nc == 0) continue;
      fs.site = w->sites_by_depth[q];
      fs.depth = d;
      fs.col = win.si1 - site.i;  // window column of pressure column 0
      fs.off = win.sj1 - site.j;  // window row of pressure row 0
      w->sites.push_back(fs);
    }
  }
  w->site_col.resize(w->sites.size());
  for (size_t q = 0; q < w->sites.size(); ++q) w->site_col[q] = w->sites[q].col;
}

}  // namespace fold_detail

namespace {

constexpr int kLanes = 8;  // cells per chunk of the cost model
// Cost model of the folded path (one core), fitted by examples/bench_kernel.py
// --calibrate: seconds per site x component x active cell, and per folded
// table cell.
constexpr double kFoldedSecondsPerMac = 0.05e-9;
constexpr double kFoldSecondsPerCell = 0.22e-9;

}  // namespace

double EstimateFoldedSeconds(const KernelTables& kt, const std::vector<StressSite>& sites,
                             int active_cells) {
  double macs = 0;
  int si0 = kt.n, si1 = -1, sj0 = kt.n, sj1 = -1;
  std::vector<std::array<bool, kNumStress>> want(kt.depths_m.size());
  for (const StressSite& s : sites) {
    macs += fold_detail::CountWanted(s.want);
    si0 = std::min(si0, s.i);
    si1 = std::max(si1, s.i);
    sj0 = std::min(sj0, s.j);
    sj1 = std::max(sj1, s.j);
    for (int c = 0; c < kNumStress; ++c)
      want[s.depth_index][c] = want[s.depth_index][c] || (s.want[c] && kt.components[c]);
  }
  if (si1 < 0) return 0.0;
  int tables = 0;
  for (const auto& w : want) tables += fold_detail::CountWanted(w);
  // The contact's box taken as a square of its active cells.
  const double side = std::sqrt(static_cast<double>(active_cells)) + kLanes;
  const double window = (side + si1 - si0) * (side + sj1 - sj0);
  return kFoldedSecondsPerMac * macs * active_cells + kFoldSecondsPerCell * tables * window;
}

}  // namespace mjtouch
