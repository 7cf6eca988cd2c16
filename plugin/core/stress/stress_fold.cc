// The folded direct path of stage 3 (stress_fold.h): the fold of the tables,
// the per-site sums in a copy per ISA, the rx cache and the driver.
//
// The canonical sum, one sequence of float operations whatever the ISA,
// layout or thread split: a site's cells in bands of kTableRowsPerBand rows
// on multiples of 8 of dy = cell row - site row; each row's products E * p
// accumulated by fused multiply-add (one rounding per term) in 16 float
// lanes (lane l: the cells at dx = l mod 16) over its chunks of 16 in
// increasing dx; the band's row sums added in row order, widened and added
// to 16 double lanes (bands in increasing dy); the 16 lanes reduced in a
// fixed order at the end. Zero cells are exact no-ops (a lane that starts at
// +0 never holds -0), so padding and which rows are summed together change
// no bit. The fold is fused too: E = fma(r_y, K_y, fma(r_x, K_x, K_p)).
// MJTOUCH_SUM_LANES=8 or 4 in the environment picks a narrower copy (tests).
#include "stress/stress_fold.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <cstring>

#include "common/exact_fma.h"
#include "common/simd.h"
#include "common/thread_pool.h"

// The vector helpers below are always inlined into the target_clones
// functions, so their by-value vector ABI never applies.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace mjtouch {
namespace {

constexpr int kLanes = 8;           // cells per chunk of the cost model
constexpr int kSumLanes = 16;       // lanes of the canonical sum (above)
constexpr int kFoldLanes = 16;      // cells per fold chunk (one AVX-512 vector)
constexpr int kSitesPerChunk = 8;
// Folded table rows per band: folded together, then read by every site; also
// the rows whose float sums are widened to double at once (a site's sum has
// ~10^3-10^4 terms; float over a few rows keeps the error ~1e-7).
constexpr int kTableRowsPerBand = 8;
// Cost model of the folded path (one core), fitted by examples/bench_kernel.py
// --calibrate: seconds per site x component x active cell, and per folded
// table cell.
constexpr double kFoldedSecondsPerMac = 0.05e-9;
constexpr double kFoldSecondsPerCell = 0.22e-9;

typedef float v16f __attribute__((vector_size(64)));
typedef double v8d __attribute__((vector_size(64)));
typedef double v16d __attribute__((vector_size(128)));

inline __attribute__((always_inline)) v16f Load16(const float* p) {
  v16f v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}

// a * b + c with one rounding (IEEE fma) in every lane: the sums' and the
// fold's one operation per term, exactly specified, so every copy below
// gives the same bits. kFma: the copy is compiled for an FMA unit; GCC
// contracts a * b + c into one vector fma there (MJTOUCH_CONTRACT), Clang
// (whose contraction is fixed where the code is parsed) vectorises fmaf
// lane by lane. Without FMA: FmaFromDouble in double vectors (exact, and
// cheaper than a fmaf call per lane).
template <bool kFma, typename V>
inline __attribute__((always_inline)) V MulAdd(V a, V b, V c) {
  if constexpr (!kFma) {
    return FmaFromDouble(a, b, c);
  } else {
#if defined(__GNUC__) && !defined(__clang__)
    return a * b + c;
#else
    V r;
    for (int l = 0; l < static_cast<int>(sizeof(V) / sizeof(float)); ++l)
      r[l] = __builtin_fmaf(a[l], b[l], c[l]);
    return r;
#endif
  }
}

template <bool kFma>
inline __attribute__((always_inline)) float MulAdd(float a, float b, float c) {
  if constexpr (kFma) {
    return __builtin_fmaf(a, b, c);
  } else {
    return FmaFromDouble(a, b, c);
  }
}

template <bool kFma>
inline __attribute__((always_inline)) v16f MulAdd(float a, v16f b, v16f c) {
  return MulAdd<kFma>(v16f{} + a, b, c);
}

// The hot functions (SumBand, the fold) in a copy per ISA: simd.h
// MJTOUCH_ISA_COPIES.

// One band of a site (the canonical sum, above): the kTableRowsPerBand
// pressure rows P + t ps (t = 0 ..; cells rlo[t] .. rhi[t], none: lo >= hi)
// against the folded rows ebuf[comp] + t ew at the same cells, in chunks of
// 16 on dx multiples of 16 (dx of pressure column x: g + x), so lane l = the
// cells at dx = l mod 16. Each row's lanes summed in float over its chunks
// in order (R rows at once, over their cells' union: independent chains, so
// one-component sites are not bound by the add latency), the rows' sums
// added in row order, then widened into the site's double lanes. Which
// zero cells or rows a chunk range adds does not change a bit (a float lane
// that starts at +0 never holds -0, and x + (+-0) = x), so the sum is the
// same sequence of operations on the nonzero products for any R, layout or
// thread split. A chunk's 16 lanes are held as 16 / W vectors of the
// machine's width W (one AVX-512 register, two AVX2 ones, four SSE2 / NEON
// ones), each term one fma (MulAdd): the same bits on every ISA. (One
// 16-float GCC vector on a narrower ISA would be lowered through the stack.)
template <int W>
struct Native {
  typedef float vf __attribute__((vector_size(W * sizeof(float))));
  static constexpr int kParts = kSumLanes / W;
  static inline __attribute__((always_inline)) vf Load(const float* p) {
    vf v;
    std::memcpy(&v, p, sizeof(v));
    return v;
  }
};

template <int W, bool kFma, int NC, int R>
inline __attribute__((always_inline)) void SiteBand(FoldSite& s, const float* const* ebuf, int ew,
                                                    const float* P, int ps, const int* rlo,
                                                    const int* rhi, int g) {
  static_assert(kTableRowsPerBand % R == 0, "rows at once must divide the band");
  typedef typename Native<W>::vf vf;
  constexpr int J = Native<W>::kParts;
  const float* erow[NC];
  for (int c = 0; c < NC; ++c) erow[c] = ebuf[s.comp[c]] + s.col;
  vf f[NC][J];
  for (int c = 0; c < NC; ++c)
    for (int j = 0; j < J; ++j) f[c][j] = vf{};
  bool any = false;
#pragma GCC unroll 8
  for (int t = 0; t < kTableRowsPerBand; t += R) {
    int lo = rlo[t], hi = rhi[t];
    for (int u = 1; u < R; ++u) {
      lo = std::min(lo, rlo[t + u]);
      hi = std::max(hi, rhi[t + u]);
    }
    if (lo >= hi) continue;  // zero rows: no-ops
    any = true;
    const int x = lo - ((g + lo) & (kSumLanes - 1));
    vf r[R][NC][J];
#pragma GCC unroll 8
    for (int u = 0; u < R; ++u)
#pragma GCC unroll 6
      for (int c = 0; c < NC; ++c)
#pragma GCC unroll 4
        for (int j = 0; j < J; ++j) r[u][c][j] = vf{};
    for (int k = x; k < hi; k += kSumLanes)
#pragma GCC unroll 8
      for (int u = 0; u < R; ++u)
#pragma GCC unroll 4
        for (int j = 0; j < J; ++j) {
          const vf p = Native<W>::Load(P + static_cast<ptrdiff_t>(t + u) * ps + k + j * W);
#pragma GCC unroll 6
          for (int c = 0; c < NC; ++c)
            r[u][c][j] = MulAdd<kFma>(
                Native<W>::Load(erow[c] + static_cast<ptrdiff_t>(t + u) * ew + k + j * W), p,
                r[u][c][j]);
        }
#pragma GCC unroll 8
    for (int u = 0; u < R; ++u)
#pragma GCC unroll 6
      for (int c = 0; c < NC; ++c)
#pragma GCC unroll 4
        for (int j = 0; j < J; ++j) f[c][j] += r[u][c][j];
  }
  if (!any) return;
  for (int c = 0; c < NC; ++c) {
    if constexpr (W == kSumLanes) {
      // Widened as one 16-lane vector, then split: GCC 12 converts an 8-float
      // half 4 lanes at a time (two converts and two shuffles more per half).
      const v16d x = __builtin_convertvector(f[c][0], v16d);
      v8d* d = reinterpret_cast<v8d*>(s.d[c]);
      d[0] += __builtin_shufflevector(x, x, 0, 1, 2, 3, 4, 5, 6, 7);
      d[1] += __builtin_shufflevector(x, x, 8, 9, 10, 11, 12, 13, 14, 15);
    } else {
      float lanes[kSumLanes];
      std::memcpy(lanes, f[c], sizeof(lanes));
      for (int l = 0; l < kSumLanes; ++l) s.d[c][l] += static_cast<double>(lanes[l]);
    }
  }
}

// A band of folded table rows (window rows [T0, T0 + kTableRowsPerBand), one
// dy block) into the sums of the sites [first, last) that read it: site q's
// pressure rows T0 - off .. (rlo / rhi: each pressure row's cells, from row
// -kTableRowsPerBand; none outside the contact).
template <int W, bool kFma>
inline __attribute__((always_inline)) void SumBandBody(FoldSite* sites, int first, int last,
                                                       const float* const* ebuf, int ew, int T0,
                                                       const float* P, int ps, const int* rlo,
                                                       const int* rhi, int x0) {
  for (int q = first; q < last; ++q) {
    FoldSite& s = sites[q];
    const int r0 = T0 - s.off;
    const float* Pr = P + static_cast<ptrdiff_t>(r0) * ps;
    const int* lo = rlo + r0 + kTableRowsPerBand;
    const int* hi = rhi + r0 + kTableRowsPerBand;
    const int g = x0 + s.col;
    switch (s.nc) {
      case 1: SiteBand<W, kFma, 1, 4>(s, ebuf, ew, Pr, ps, lo, hi, g); break;
      case 2: SiteBand<W, kFma, 2, 2>(s, ebuf, ew, Pr, ps, lo, hi, g); break;
      case 3: SiteBand<W, kFma, 3, 2>(s, ebuf, ew, Pr, ps, lo, hi, g); break;
      case 4: SiteBand<W, kFma, 4, 1>(s, ebuf, ew, Pr, ps, lo, hi, g); break;
      case 5: SiteBand<W, kFma, 5, 1>(s, ebuf, ew, Pr, ps, lo, hi, g); break;
      default: SiteBand<W, kFma, 6, 1>(s, ebuf, ew, Pr, ps, lo, hi, g); break;
    }
  }
}

MJTOUCH_ISA_COPIES(SumBand,
                   (FoldSite* sites, int first, int last, const float* const* ebuf, int ew,
                    int T0, const float* P, int ps, const int* rlo, const int* rhi, int x0),
                   (sites, first, last, ebuf, ew, T0, P, ps, rlo, rhi, x0))

inline __attribute__((always_inline)) void Store(float* p, v16f v) {
  std::memcpy(p, &v, sizeof(v));
}

// 16 cells [x, x + 16) of a table row read forwards (p[x] ...) or backwards
// (p[-x] ...).
template <bool kReversed>
inline __attribute__((always_inline)) v16f Cells(const float* p, int x) {
  if (!kReversed) return Load16(p + x);
  const v16f v = Load16(p - x - (kFoldLanes - 1));
  return __builtin_shufflevector(v, v, 15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1,
                                 0);  // (GCC and Clang)
}

// e[x] = one(x) for x in [0, len), 16 cells at a time (chunk(x): cells x ..
// x + 15, the same operations per cell as one: elementwise, so the same bits
// at any width), with the stores on e's 64-byte boundaries: a first chunk at
// 0, then from e's first boundary on, a last chunk ending at len;
// overlapping chunks rewrite the same values. No cell outside [0, len) is
// read or written and there is no scalar tail: folded rows are ~100 cells,
// and the vectorised loops' tails, alias checks and cache-line-split stores
// would cost about as much as the cells.
template <typename Chunk, typename One>
inline __attribute__((always_inline)) void FoldCells(int len, float* e, Chunk chunk, One one) {
  if (len < kFoldLanes) {
    for (int x = 0; x < len; ++x) e[x] = one(x);
    return;
  }
  Store(e, chunk(0));
  int x = kFoldLanes -
          static_cast<int>(reinterpret_cast<uintptr_t>(e) / sizeof(float) & (kFoldLanes - 1));
  for (; x + kFoldLanes <= len; x += kFoldLanes) Store(e + x, chunk(x));
  if (x < len) Store(e + len - kFoldLanes, chunk(len - kFoldLanes));
}

// e[x] = sign fma(ry, ky[x], fma(rx, kx[x], kp[x])) (float; sign +-1, exact), or
// sign kp[x] without shear; kReversed: from a mirrored source read backwards
// (k[-x]), a table row at negative offsets from its row at positive ones.
template <bool kFma, bool kReversed>
inline __attribute__((always_inline)) void FoldRowCells(const float* kp, const float* kx,
                                                        const float* ky, float rx, float ry,
                                                        float sign, bool shear, int len,
                                                        float* e) {
  const int d = kReversed ? -1 : 1;
  if (shear) {
    FoldCells(
        len, e,
        [&](int x) {
          return sign * MulAdd<kFma>(ry, Cells<kReversed>(ky, x),
                                     MulAdd<kFma>(rx, Cells<kReversed>(kx, x),
                                                  Cells<kReversed>(kp, x)));
        },
        [&](int x) {
          return sign * MulAdd<kFma>(ry, ky[d * x], MulAdd<kFma>(rx, kx[d * x], kp[d * x]));
        });
  } else if (!kReversed && sign > 0) {
    std::memcpy(e, kp, sizeof(float) * len);
  } else {
    FoldCells(
        len, e, [&](int x) { return sign * Cells<kReversed>(kp, x); },
        [&](int x) { return sign * kp[d * x]; });
  }
}

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

// Folded rows dy0 .. dy0 + rows - 1 (rows ew apart) at dx = x0 .. x0 + w - 1
// (x0, w multiples of 16; e 64-byte aligned) from the rx cache h of one
// (depth, component): e = sp fma(sp sy ry, ky, h), the same float operations
// as FoldRowCells' fma(b, ky, fma(a, kx, kp)) on the same h, so the same bits.
template <int, bool kFma>  // (the fold's chunks are 16 floats on every ISA)
inline __attribute__((always_inline)) void FoldCachedRowsBody(const float* h, int n,
                                                              StressComponent comp, int dy0,
                                                              int rows, int x0, int w, float ry,
                                                              float* e, int ew) {
  const int half = RxCacheHalf(n);
  const size_t stride = RxCacheStride(n);
  // Chunk ranges [0, a): below the cache (zero), [a, m): dx < 0, [m, z): dx
  // >= 0, [z, w): above (zero); the same for every row of the band.
  const int a = std::clamp(-half - x0, 0, w), m = std::clamp(-x0, a, w),
            z = std::clamp(half - x0, m, w);
  const float mp0 = MirrorSign(0, kLoadPressure, comp), mp1 = MirrorSign(1, kLoadPressure, comp);
  const float my0 = MirrorSign(0, kLoadShearY, comp), my1 = MirrorSign(1, kLoadShearY, comp);
  for (int t = 0; t < rows; ++t) {
    float* et = e + static_cast<size_t>(t) * ew;
    const int dy = dy0 + t, ady = dy < 0 ? -dy : dy;
    if (ady > n - 1) {
      std::fill(et, et + w, 0.0f);
      continue;
    }
    if (a > 0) std::fill(et, et + a, 0.0f);
    if (z < w) std::fill(et + z, et + w, 0.0f);
    const float* hr = h + static_cast<size_t>(ady) * stride + (x0 + half);  // at column 0
    const float* ky = h + static_cast<size_t>(ady) * stride + 2 * half;      // at |dx| = 0
    for (int side = 1; side >= 0; --side) {  // dx >= 0 (its ky lines then in L1), dx < 0
      float sp = 1, sy = 1;
      if (side == 0) {
        sp *= mp0;
        sy *= my0;
      }
      if (dy < 0) {
        sp *= mp1;
        sy *= my1;
      }
      const float b = sp * sy * ry;
      const int lo = side ? m : a, hi = side ? z : m;
      if (side == 1) {
        const float* k = ky + x0;
        if (sp > 0) {
          for (int x = lo; x < hi; x += kFoldLanes)
            Store(et + x, MulAdd<kFma>(b, Load16(k + x), Load16(hr + x)));
        } else {
          for (int x = lo; x < hi; x += kFoldLanes)
            Store(et + x, -MulAdd<kFma>(b, Load16(k + x), Load16(hr + x)));
        }
      } else {
        // cells dx = x0 + x + j (j = 0 .. 15): ky at |dx| = -(x0 + x) - j
        const float* k = ky - x0;
        if (sp > 0) {
          for (int x = lo; x < hi; x += kFoldLanes)
            Store(et + x, MulAdd<kFma>(b, Cells<true>(k, x), Load16(hr + x)));
        } else {
          for (int x = lo; x < hi; x += kFoldLanes)
            Store(et + x, -MulAdd<kFma>(b, Cells<true>(k, x), Load16(hr + x)));
        }
      }
    }
  }
}

MJTOUCH_ISA_COPIES(FoldCachedRows,
                   (const float* h, int n, StressComponent comp, int dy0, int rows, int x0,
                    int w, float ry, float* e, int ew),
                   (h, n, comp, dy0, rows, x0, w, ry, e, ew))

// One row of a folded window (offset dy, columns dx = x0 .. x0 + w - 1) from
// the tables' rows at |dy| and columns |dx| only (KernelTables::
// mirror_symmetric): the signs of the reflections folded into the ratios,
// E = sp (Kp + (sp sx rx) Kx + (sp sy ry) Ky), exactly the value the full
// tables give when they are mirror images.
template <bool kFma>
inline __attribute__((always_inline)) void FoldMirroredRow(const KernelTables& kt, int d,
                                                           StressComponent comp, int dy, int x0,
                                                           int w, float rx, float ry, bool shear,
                                                           float* e) {
  const int n = kt.n, L = 2 * n - 1;
  const int ady = dy < 0 ? -dy : dy;
  if (ady > n - 1) {
    std::fill(e, e + w, 0.0f);
    return;
  }
  // Zero beyond the tables' offsets (rarely any); the two sides below write
  // the rest.
  const int z0 = std::clamp(-(n - 1) - x0, 0, w), z1 = std::clamp(n - x0, 0, w);
  if (z0 > 0) std::fill(e, e + z0, 0.0f);
  if (z1 < w) std::fill(e + z1, e + w, 0.0f);
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
      FoldRowCells<kFma, false>(Kp + lo, Kx + lo, Ky + lo, a, b, sp, shear, hi - lo + 1,
                          e + (lo - x0));
    } else {
      // e at dx = lo .. hi reads the positive-offset row at -lo .. -hi.
      FoldRowCells<kFma, true>(Kp - lo, Kx - lo, Ky - lo, a, b, sp, shear, hi - lo + 1,
                         e + (lo - x0));
    }
  }
}

template <int, bool kFma>
inline __attribute__((always_inline)) void FoldMirroredRowsBody(
    const KernelTables& kt, int d, StressComponent comp, int dy0, int rows, int x0, int w,
    float rx, float ry, bool shear, float* e, int ew) {
  for (int t = 0; t < rows; ++t)
    FoldMirroredRow<kFma>(kt, d, comp, dy0 + t, x0, w, rx, ry, shear,
                          e + static_cast<size_t>(t) * ew);
}

// Rows dy0 .. dy0 + rows - 1 of a folded window into e (rows ew apart): one
// dispatch per band, not two per row side.
MJTOUCH_ISA_COPIES(FoldMirroredRows,
                   (const KernelTables& kt, int d, StressComponent comp, int dy0, int rows,
                    int x0, int w, float rx, float ry, bool shear, float* e, int ew),
                   (kt, d, comp, dy0, rows, x0, w, rx, ry, shear, e, ew))

// The first 64-byte aligned float at or after p (buffers allocate 16 more).
float* AlignUp64(float* p) {
  const uintptr_t a = reinterpret_cast<uintptr_t>(p);
  return p + ((64 - a % 64) % 64) / sizeof(float);
}

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
    float* const base = AlignUp64(buf.data()) + kSumLanes + (win.x0 & (kSumLanes - 1)) +
                        (legacy ? 1 : 0);
    float* ebuf[kNumStress];
    bool comps[kNumStress] = {};
    for (int q = job.begin; q < job.end; ++q) {
      for (int c = 0; c < fs[q].nc; ++c) comps[fs[q].comp[c]] = true;
      std::memset(fs[q].d, 0, sizeof(fs[q].d[0]) * fs[q].nc);
    }
    for (int c = 0; c < kNumStress; ++c)
      ebuf[c] = base + static_cast<size_t>(c) * band * ew;
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
                         static_cast<StressComponent>(c), T0 + win.y0, band, win.x0 + c0,
                         c1 - c0, ry, ebuf[c] + c0, ew);
        else
          FoldMirroredRows(kt, d, static_cast<StressComponent>(c), T0 + win.y0, band,
                           win.x0 + c0, c1 - c0, rx, ry, shear, ebuf[c] + c0, ew);
      }
      SumBand(fs, first, last, ebuf, ew, T0, P0, ps, w->row_lo.data(), w->row_hi.data(),
              win.x0);
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

void ReferenceDirectStresses(const KernelTables& kt, const std::vector<StressSite>& sites,
                             const ActiveRuns& runs, const float* pressure,
                             const float* shear_x, const float* shear_y, int threads,
                             Stress6* out) {
  for (size_t s = 0; s < sites.size(); ++s) out[s].fill(0.0);
  // Component-major, depth by depth: the three tables of one (depth,
  // component), ~0.8 MB at n = 128, stay in cache while its sites read their
  // windows (site-major order would stream all 18 tables per site).
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
