// The folded direct path of stage 3 (stress_fold.h): the driver, which lays
// out the pressure window, plans the jobs and runs the kernels over the
// bands of folded rows, and the reference direct sum split the same way.
#include "stress/stress_fold.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "common/thread_pool.h"
#include "stress/stress_fold_internal.h"

namespace mjtouch {

using namespace fold_detail;

namespace {

// The folded sums of one field: with shear, the pressure field against
// Kp + slip_x Kx + slip_y Ky; without, the field against load `single`'s
// table alone.
void FoldedSums(const KernelTables& kt, const std::vector<StressSite>& sites,
                const ActiveRuns& runs, const float* pressure, bool shear, double slip_x,
                double slip_y, SurfaceLoad single, int threads, FoldScratch* w, Stress6* out) {
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
  const int pw = i1 - i0 + 1;
  // Rows of ps cells, 64-byte aligned, with kSumLanes zero cells on each side
  // and kTableRowsPerBand zero rows above and below, which the sums' chunks
  // and bands read (SumBand: zero cells are exact no-ops).
  const int band = kTableRowsPerBand;
  const int ps = (pw + 2 * kSumLanes + kSumLanes - 1) / kSumLanes * kSumLanes;
  w->pressure.assign(static_cast<size_t>(rows + 2 * band) * ps + 16, 0.0f);
  float* const P0 = AlignUp64(w->pressure.data()) + static_cast<size_t>(band) * ps + kSumLanes;
  // Each pressure row's cells (none: lo >= hi), from row -band to rows + band.
  w->row_lo.assign(rows + 2 * band, pw);
  w->row_hi.assign(rows + 2 * band, 0);
  for (size_t r = 0; r < runs.row.size(); ++r) {
    const int y = runs.row[r] - j0;
    const int b = runs.begin[r] - i0, e = runs.end[r] - i0;
    std::copy(pressure + static_cast<size_t>(runs.row[r]) * n + runs.begin[r],
              pressure + static_cast<size_t>(runs.row[r]) * n + runs.end[r],
              P0 + static_cast<size_t>(y) * ps + b);
    w->row_lo[y + band] = std::min(w->row_lo[y + band], b);
    w->row_hi[y + band] = std::max(w->row_hi[y + band], e);
  }
  // Each band's cells: band_lo / band_hi[r] over pressure rows r .. r + band - 1
  // (indices as row_lo's).
  w->band_lo.assign(rows + band + 1, pw);
  w->band_hi.assign(rows + band + 1, 0);
  for (int r = 0; r <= rows + band; ++r)
    for (int t = 0; t < band; ++t) {
      w->band_lo[r] = std::min(w->band_lo[r], w->row_lo[r + t]);
      w->band_hi[r] = std::max(w->band_hi[r], w->row_hi[r + t]);
    }
  // Sites grouped by depth, each depth's window of table offsets and the
  // sites' states: fixed by the sites, so kept while they are unchanged.
  auto same = [](const StressSite& a, const StressSite& b) {
    return a.i == b.i && a.j == b.j && a.depth_index == b.depth_index && a.want == b.want;
  };
  if (w->key_tables != &kt || w->key_components != kt.components ||
      w->window.size() != static_cast<size_t>(D) || w->key_sites.size() != sites.size() ||
      !std::equal(sites.begin(), sites.end(), w->key_sites.begin(), same)) {
    SortSites(kt, sites, w);
    w->h_calls = 0;  // the rx cache covers the old sites' components
    w->h_valid = false;
    w->key_tables = &kt;
    w->key_components = kt.components;
    w->key_sites = sites;
  }
  for (int d = 0; d < D; ++d) {
    auto& win = w->window[d];
    if (win.si1 < 0) continue;
    win.x0 = i0 - win.si1;
    win.y0 = j0 - win.sj1;
    win.w = pw + win.si1 - w->si0[d];
    win.h = rows + win.sj1 - w->sj0[d];
  }
  // Jobs: one per depth on one thread (every site of a depth shares each
  // folded row), split into `threads` site ranges otherwise (each range folds
  // the rows it reads: a cell's folded value does not depend on which rows
  // or columns are folded with it, and a site's sum not on its neighbours,
  // so the output is bit-identical for any split).
  w->jobs.clear();
  for (size_t a = 0; a < w->sites.size();) {
    size_t b = a;
    while (b < w->sites.size() && w->sites[b].depth == w->sites[a].depth) ++b;
    const int count = static_cast<int>(b - a);
    const int groups = std::max(1, std::min(threads, count / kSitesPerChunk));
    for (int g = 0; g < groups; ++g)
      w->jobs.push_back({static_cast<int>(a) + count * g / groups,
                         static_cast<int>(a) + count * (g + 1) / groups});
    a = b;
  }
  if (w->rowbuf.size() < w->jobs.size()) w->rowbuf.resize(w->jobs.size());
  const float rx = static_cast<float>(slip_x), ry = static_cast<float>(slip_y);
  const bool legacy = w->fold_legacy;
  const auto t0 = std::chrono::steady_clock::now();
  if (shear && !legacy) UpdateRxCache(kt, rx, w);
  const bool use_h = shear && !legacy && w->h_valid;
  ThreadPool::Shared().Run(static_cast<int>(w->jobs.size()), threads, [&](int k) {
    const FoldScratch::Job job = w->jobs[k];
    FoldSite* fs = w->sites.data();
    const int d = fs[job.begin].depth;
    const auto& win = w->window[d];
    std::vector<float>& buf = w->rowbuf[k];
    // Folded rows of ew cells, 64-byte aligned at dx multiples of 16 (window
    // column x: dx = win.x0 + x), room for whole chunks on each side (the
    // chunks reach 15 cells beyond a site's span); legacy: one cell off
    // (every table load splits a cache line; the same bits).
    const int ew = (win.w + 4 * kSumLanes) / kSumLanes * kSumLanes;
    buf.resize(static_cast<size_t>(kNumStress) * band * ew + 32);
    float* const base =
        AlignUp64(buf.data()) + kSumLanes + (win.x0 & (kSumLanes - 1)) + (legacy ? 1 : 0);
    float* ebuf[kNumStress];
    bool comps[kNumStress] = {};
    for (int q = job.begin; q < job.end; ++q) {
      for (int c = 0; c < fs[q].nc; ++c) comps[fs[q].comp[c]] = true;
      std::memset(fs[q].d, 0, sizeof(fs[q].d[0]) * fs[q].nc);
    }
    for (int c = 0; c < kNumStress; ++c) ebuf[c] = base + static_cast<size_t>(c) * band * ew;
    const int* blo = w->band_lo.data();  // a band's pressure rows' cells
    const int* bhi = w->band_hi.data();
    const int* col = w->site_col.data();  // fs[q].col, contiguous
    int first = job.begin, last = job.begin;
    // Bands on dy multiples of kTableRowsPerBand (window row T: dy = T + y0).
    const int t_begin = fs[job.begin].off - (((fs[job.begin].off + win.y0) % band) + band) % band;
    const int t_end = fs[job.end - 1].off + rows;
    for (int T0 = t_begin; T0 < t_end; T0 += band) {
      const int T1 = T0 + band;
      while (last < job.end && fs[last].off < T1) ++last;
      while (first < last && fs[first].off + rows <= T0) ++first;
      // Fold the band over the columns its sites read.
      // Only the chunks (dx multiples of 16) that the sites' rows in this band
      // read: whole chunks, so the fold's stores are aligned too.
      int c0 = win.w + kSumLanes, c1 = -kSumLanes;
      for (int q = first; q < last; ++q) {
        const int r = T0 - fs[q].off + band;
        if (blo[r] >= bhi[r]) continue;
        c0 = std::min(c0, col[q] + blo[r]);
        c1 = std::max(c1, col[q] + bhi[r]);
      }
      if (c0 >= c1) continue;  // no site reads this band
      c0 = ((win.x0 + c0) & ~(kSumLanes - 1)) - win.x0;
      c1 = ((win.x0 + c1 + kSumLanes - 1) & ~(kSumLanes - 1)) - win.x0;
      for (int c = 0; c < kNumStress; ++c) {
        if (!comps[c]) continue;
        if (use_h)
          FoldCachedRows(w->h.data() + w->h_pad + w->h_offset[d * kNumStress + c], n,
                         static_cast<StressComponent>(c), T0 + win.y0, band, win.x0 + c0, c1 - c0,
                         ry, ebuf[c] + c0, ew);
        else
          FoldMirroredRows(kt, d, static_cast<StressComponent>(c), T0 + win.y0, band, win.x0 + c0,
                           c1 - c0, rx, ry, shear, single, ebuf[c] + c0, ew);
      }
      SumBand(fs, first, last, ebuf, ew, T0, P0, ps, w->row_lo.data(), w->row_hi.data(), win.x0);
    }
    // The 16 double lanes of each component, in one fixed order.
    for (int q = job.begin; q < job.end; ++q)
      for (int c = 0; c < fs[q].nc; ++c) {
        const double* l = fs[q].d[c];
        double a[8];
        for (int i = 0; i < 8; ++i) a[i] = l[i] + l[i + 8];
        out[fs[q].site][fs[q].comp[c]] =
            ((a[0] + a[4]) + (a[2] + a[6])) + ((a[1] + a[5]) + (a[3] + a[7]));
      }
  });
  w->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The phase tables of the coarse correction (FoldScratch::coarse_tables):
// per wanted (depth, load, component) and lattice phase (px, py) (a site's
// cell index mod s), the table at offsets (s e - px, s f - py), e, f in
// [-E, E], rows of 2E + 1, zero beyond the table; a site then reads its
// nodes' entries in contiguous rows.
// f rounded to bfloat16 (to nearest, ties to even; the tables hold no NaN).
uint16_t ToBf16(float f) {
  uint32_t u;
  std::memcpy(&u, &f, sizeof(u));
  u += 0x7FFFu + ((u >> 16) & 1u);
  return static_cast<uint16_t>(u >> 16);
}

int CoarseReach(int n, int s) { return (n - 1 + s) / s + 1; }

void CoarseShearTables(const KernelTables& kt, const std::vector<StressSite>& sites,
                       FoldScratch* w) {
  const int D = static_cast<int>(kt.depths_m.size());
  std::vector<std::array<bool, kNumStress>> want(D);
  double depth_m = HUGE_VAL;  // the shallowest site's
  for (const StressSite& st : sites) {
    bool any = false;
    for (int c = 0; c < kNumStress; ++c) {
      want[st.depth_index][c] |= st.want[c] && kt.components[c];
      any |= st.want[c] && kt.components[c];
    }
    if (any) depth_m = std::min(depth_m, kt.depths_m[st.depth_index]);
  }
  if (w->coarse_key == &kt && w->coarse_want == want) return;
  w->coarse_cells = std::clamp(static_cast<int>(kCoarseSpacingPerDepth * depth_m / kt.pitch_m), 1,
                               kMaxCoarseCells);
  const int s = w->coarse_cells, n = kt.n, L = 2 * n - 1, E = CoarseReach(n, s), W = 2 * E + 1;
  const size_t block = static_cast<size_t>(s) * s * W * W;
  w->coarse_offset.assign(static_cast<size_t>(D) * 2 * kNumStress, -1);
  size_t count = 0;
  for (int d = 0; d < D; ++d)
    for (int l = 0; l < 2; ++l)
      for (int c = 0; c < kNumStress; ++c)
        if (want[d][c]) w->coarse_offset[(d * 2 + l) * kNumStress + c] = count++ * block;
  w->coarse_tables.assign(count * block + 16, 0);
  for (int d = 0; d < D; ++d)
    for (int l = 0; l < 2; ++l)
      for (int c = 0; c < kNumStress; ++c) {
        const long off = w->coarse_offset[(d * 2 + l) * kNumStress + c];
        if (off < 0) continue;
        const float* K =
            kt.At(d, l == 0 ? kLoadShearX : kLoadShearY, static_cast<StressComponent>(c));
        uint16_t* T = w->coarse_tables.data() + off;
        for (int py = 0; py < s; ++py)
          for (int px = 0; px < s; ++px)
            for (int f = -E; f <= E; ++f) {
              const int dj = s * f - py;
              if (dj < -(n - 1) || dj > n - 1) continue;
              uint16_t* row = T + (static_cast<size_t>(py * s + px) * W + (f + E)) * W;
              for (int e = -E; e <= E; ++e) {
                const int di = s * e - px;
                if (di < -(n - 1) || di > n - 1) continue;
                row[e + E] = ToBf16(K[static_cast<size_t>(dj + n - 1) * L + (di + n - 1)]);
              }
            }
      }
  w->coarse_key = &kt;
  w->coarse_want = want;
}

}  // namespace

void FoldedSplitStresses(const KernelTables& kt, const std::vector<StressSite>& sites,
                         const ActiveRuns& runs, const float* pressure, const float* shear_x,
                         const float* shear_y, double slip_x, double slip_y, int threads,
                         FoldScratch* w, Stress6* out) {
  FoldedSums(kt, sites, runs, pressure, true, slip_x, slip_y, kLoadPressure, threads, w, out);
  if (runs.row.empty() || sites.empty()) return;
  const double seconds = w->seconds;
  const auto t0 = std::chrono::steady_clock::now();
  CoarseShearTables(kt, sites, w);
  const int s = w->coarse_cells, n = kt.n, E = CoarseReach(n, s), W = 2 * E + 1;
  // Each cell's weights on the nodes a - 1 .. a + 2 (a = i / s) along one
  // axis: quadratic Lagrange on the nearest node and its two neighbours
  // (force and first and second moments kept); separable.
  double wt[kMaxCoarseCells][4] = {};
  for (int r = 0; r < s; ++r) {
    const bool up = 2 * r > s;  // nearest node a + 1
    const double t = static_cast<double>(r) / s - (up ? 1.0 : 0.0);
    const int k = up ? 2 : 1;  // the nearest node's slot
    wt[r][k - 1] = 0.5 * t * (t - 1.0);
    wt[r][k] = 1.0 - t * t;
    wt[r][k + 1] = 0.5 * t * (t + 1.0);
  }
  int i0 = n, i1 = -1;
  for (size_t r = 0; r < runs.row.size(); ++r) {
    i0 = std::min(i0, runs.begin[r]);
    i1 = std::max(i1, runs.end[r] - 1);
  }
  const int j0 = runs.row.front(), j1 = runs.row.back();
  const int a0 = i0 / s - 1, b0 = j0 / s - 1;
  const int na = i1 / s + 3 - a0, nb = j1 / s + 3 - b0;
  const int vs = (na + kSumLanes - 1) / kSumLanes * kSumLanes;
  // Along x into one row of nodes per cell row, then along y.
  const size_t rows = static_cast<size_t>(j1 - j0 + 1);
  w->row_nodes_x.assign(rows * vs, 0.0);
  w->row_nodes_y.assign(rows * vs, 0.0);
  const double rx = static_cast<float>(slip_x), ry = static_cast<float>(slip_y);
  for (size_t r = 0; r < runs.row.size(); ++r) {
    const int j = runs.row[r];
    double* ox = w->row_nodes_x.data() + (j - j0) * vs;
    double* oy = w->row_nodes_y.data() + (j - j0) * vs;
    for (int i = runs.begin[r]; i < runs.end[r]; ++i) {
      const size_t k = static_cast<size_t>(j) * n + i;
      // (the fold's float ratios, so that the two parts add to the field's stress)
      const double qx = shear_x[k] - rx * pressure[k];
      const double qy = shear_y[k] - ry * pressure[k];
      const double* c = wt[i % s];
      const int a = i / s - 1 - a0;
      for (int t = 0; t < 4; ++t) {
        ox[a + t] += c[t] * qx;
        oy[a + t] += c[t] * qy;
      }
    }
  }
  w->node_sum_x.assign(static_cast<size_t>(vs) * nb, 0.0);
  w->node_sum_y.assign(w->node_sum_x.size(), 0.0);
  for (int j = j0; j <= j1; ++j) {
    const double* c = wt[j % s];
    const double* ix = w->row_nodes_x.data() + (j - j0) * vs;
    const double* iy = w->row_nodes_y.data() + (j - j0) * vs;
    for (int t = 0; t < 4; ++t) {
      if (c[t] == 0.0) continue;
      double* ox = w->node_sum_x.data() + static_cast<size_t>(j / s - 1 + t - b0) * vs;
      double* oy = w->node_sum_y.data() + static_cast<size_t>(j / s - 1 + t - b0) * vs;
      for (int a = 0; a < na; ++a) {
        ox[a] += c[t] * ix[a];
        oy[a] += c[t] * iy[a];
      }
    }
  }
  w->node_x.assign(w->node_sum_x.begin(), w->node_sum_x.end());
  w->node_y.assign(w->node_sum_y.begin(), w->node_sum_y.end());
  const int chunks =
      std::max(1, std::min(threads, static_cast<int>(sites.size()) / kSitesPerChunk));
  ThreadPool::Shared().Run(chunks, threads, [&](int k) {
    const size_t q0 = sites.size() * k / chunks, q1 = sites.size() * (k + 1) / chunks;
    for (size_t q = q0; q < q1; ++q) {
      const StressSite& st = sites[q];
      const int qi = st.i / s, qj = st.j / s;
      const int phase = (st.j - qj * s) * s + (st.i - qi * s);
      // node (a0 + a, b0 + b) at e = a0 + a - qi, f = b0 + b - qj
      const long first = (static_cast<long>(phase) * W + (b0 - qj + E)) * W + (a0 - qi + E);
      const uint16_t* tx[kNumStress];
      const uint16_t* ty[kNumStress];
      int comp[kNumStress], nc = 0;
      for (int c = 0; c < kNumStress; ++c) {
        if (!st.want[c] || !kt.components[c]) continue;
        const uint16_t* base = w->coarse_tables.data() + first;
        tx[nc] = base + w->coarse_offset[(st.depth_index * 2 + 0) * kNumStress + c];
        ty[nc] = base + w->coarse_offset[(st.depth_index * 2 + 1) * kNumStress + c];
        comp[nc++] = c;
      }
      double sum[kNumStress];
      CoarseDots(tx, ty, nc, W, w->node_x.data(), w->node_y.data(), vs, nb, vs, sum);
      for (int c = 0; c < nc; ++c) out[q][comp[c]] += sum[c];
    }
  });
  w->seconds =
      seconds + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void FoldedDirectStresses(const KernelTables& kt, const std::vector<StressSite>& sites,
                          const ActiveRuns& runs, const float* pressure, bool shear, double slip_x,
                          double slip_y, int threads, FoldScratch* w, Stress6* out) {
  FoldedSums(kt, sites, runs, pressure, shear, slip_x, slip_y, kLoadPressure, threads, w, out);
}

void ReferenceDirectStresses(const KernelTables& kt, const std::vector<StressSite>& sites,
                             const ActiveRuns& runs, const float* pressure, const float* shear_x,
                             const float* shear_y, int threads, Stress6* out) {
  for (size_t s = 0; s < sites.size(); ++s) out[s].fill(0.0);
  // Component-major, depth by depth: the three tables of one (depth,
  // component), ~0.8 MB at n = 128, stay in cache while its sites read their
  // windows (site-major order would stream all 18 tables per site).
  struct Job {
    int d, c, s0, s1;
  };
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

}  // namespace mjtouch
