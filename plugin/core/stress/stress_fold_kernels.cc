// The folded path's kernels (stress_fold.h), in a copy per ISA: the sums of
// a band of table rows into the sites' lanes (SumBand) and the fold of the
// tables into one effective table (FoldMirroredRows, or from the rx cache
// FoldCachedRows).
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
#include <algorithm>
#include <cstdint>
#include <cstring>

#include "common/exact_fma.h"
#include "common/simd.h"
#include "stress/stress_fold_internal.h"

// The vector helpers below are always inlined into the per-ISA copies, so
// their by-value vector ABI never applies.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace mjtouch {
namespace fold_detail {

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
                   (FoldSite * sites, int first, int last, const float* const* ebuf, int ew, int T0,
                    const float* P, int ps, const int* rlo, const int* rhi, int x0),
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
                                                        float sign, bool shear, int len, float* e) {
  const int d = kReversed ? -1 : 1;
  if (shear) {
    FoldCells(
        len, e,
        [&](int x) {
          return sign *
                 MulAdd<kFma>(ry, Cells<kReversed>(ky, x),
                              MulAdd<kFma>(rx, Cells<kReversed>(kx, x), Cells<kReversed>(kp, x)));
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
    const float* ky = h + static_cast<size_t>(ady) * stride + 2 * half;     // at |dx| = 0
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
                   (const float* h, int n, StressComponent comp, int dy0, int rows, int x0, int w,
                    float ry, float* e, int ew),
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
                                                           SurfaceLoad single, float* e) {
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
  // without shear: the table of load `single` alone (its mirror signs)
  const SurfaceLoad lp = shear ? kLoadPressure : single;
  const float* Kp = kt.At(d, lp, comp) + row;
  const float* Kx = kt.At(d, kLoadShearX, comp) + row;
  const float* Ky = kt.At(d, kLoadShearY, comp) + row;
  for (int side = 0; side < 2; ++side) {  // dx >= 0, then dx < 0
    const int lo = side == 0 ? std::max(0, x0) : std::max(-(n - 1), x0);
    const int hi = side == 0 ? std::min(n - 1, x0 + w - 1) : std::min(-1, x0 + w - 1);
    if (lo > hi) continue;
    float sp = 1, sx = 1, sy = 1;
    if (side == 1) {
      sp *= MirrorSign(0, lp, comp);
      sx *= MirrorSign(0, kLoadShearX, comp);
      sy *= MirrorSign(0, kLoadShearY, comp);
    }
    if (dy < 0) {
      sp *= MirrorSign(1, lp, comp);
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
    const KernelTables& kt, int d, StressComponent comp, int dy0, int rows, int x0, int w, float rx,
    float ry, bool shear, SurfaceLoad single, float* e, int ew) {
  for (int t = 0; t < rows; ++t)
    FoldMirroredRow<kFma>(kt, d, comp, dy0 + t, x0, w, rx, ry, shear, single,
                          e + static_cast<size_t>(t) * ew);
}

// Rows dy0 .. dy0 + rows - 1 of a folded window into e (rows ew apart): one
// dispatch per band, not two per row side.
MJTOUCH_ISA_COPIES(FoldMirroredRows,
                   (const KernelTables& kt, int d, StressComponent comp, int dy0, int rows, int x0,
                    int w, float rx, float ry, bool shear, SurfaceLoad single, float* e, int ew),
                   (kt, d, comp, dy0, rows, x0, w, rx, ry, shear, single, e, ew))

// The coarse correction's sums (stress_fold.h FoldedSplitStresses): per
// component, over the node rows, the x then the y table row against the
// node fields in chunks of 16 (lane l: node column l mod 16), one fma per
// term in 16 float lanes, the tables in bfloat16 (half the memory traffic;
// 2^-9 per entry, on a correction that is a small part of the stress) (a
// few hundred terms in float cost it ~1e-7 of itself), then the lanes
// widened and reduced in a fixed order: the same bits on every ISA. The
// components share the node loads.
template <int W>
struct NativeU {
  typedef uint32_t vu __attribute__((vector_size(W * sizeof(uint32_t))));
};

// W bfloat16 values (the high halves of floats) as W floats: exact.
template <int W>
inline __attribute__((always_inline)) typename Native<W>::vf LoadBf16(const uint16_t* p) {
  typename NativeU<W>::vu u;
  for (int l = 0; l < W; ++l) u[l] = static_cast<uint32_t>(p[l]) << 16;
  typename Native<W>::vf f;
  std::memcpy(&f, &u, sizeof(f));
  return f;
}

template <int W, bool kFma, int NC>
inline __attribute__((always_inline)) void CoarseDotsN(const uint16_t* const* tx,
                                                       const uint16_t* const* ty, long tstride,
                                                       const float* vx, const float* vy,
                                                       int vstride, int rows, int cols,
                                                       double* result) {
  using N = Native<W>;
  using vf = typename N::vf;
  vf acc[NC][N::kParts] = {};
  for (int b = 0; b < rows; ++b) {
    const float* ux = vx + static_cast<long>(b) * vstride;
    const float* uy = vy + static_cast<long>(b) * vstride;
    const long t = b * tstride;
    for (int a = 0; a < cols; a += kSumLanes)
      for (int p = 0; p < N::kParts; ++p) {
        const int o = a + p * W;
        const vf x = N::Load(ux + o), y = N::Load(uy + o);
        for (int c = 0; c < NC; ++c) {
          acc[c][p] = MulAdd<kFma>(LoadBf16<W>(tx[c] + t + o), x, acc[c][p]);
          acc[c][p] = MulAdd<kFma>(LoadBf16<W>(ty[c] + t + o), y, acc[c][p]);
        }
      }
  }
  for (int c = 0; c < NC; ++c) {
    double lanes[kSumLanes];
    for (int p = 0; p < N::kParts; ++p)
      for (int l = 0; l < W; ++l) lanes[p * W + l] = acc[c][p][l];
    double a8[8];
    for (int i = 0; i < 8; ++i) a8[i] = lanes[i] + lanes[i + 8];
    result[c] = ((a8[0] + a8[4]) + (a8[2] + a8[6])) + ((a8[1] + a8[5]) + (a8[3] + a8[7]));
  }
}

template <int W, bool kFma>
inline __attribute__((always_inline)) void CoarseDotsBody(const uint16_t* const* tx,
                                                          const uint16_t* const* ty, int nc,
                                                          long tstride, const float* vx,
                                                          const float* vy, int vstride, int rows,
                                                          int cols, double* result) {
  for (int c = 0; c < nc;) {
    const int left = nc - c;
    if (left >= 3) {
      CoarseDotsN<W, kFma, 3>(tx + c, ty + c, tstride, vx, vy, vstride, rows, cols, result + c);
      c += 3;
    } else if (left == 2) {
      CoarseDotsN<W, kFma, 2>(tx + c, ty + c, tstride, vx, vy, vstride, rows, cols, result + c);
      c += 2;
    } else {
      CoarseDotsN<W, kFma, 1>(tx + c, ty + c, tstride, vx, vy, vstride, rows, cols, result + c);
      c += 1;
    }
  }
}

MJTOUCH_ISA_COPIES(CoarseDots,
                   (const uint16_t* const* tx, const uint16_t* const* ty, int nc, long tstride,
                    const float* vx, const float* vy, int vstride, int rows, int cols,
                    double* result),
                   (tx, ty, nc, tstride, vx, vy, vstride, rows, cols, result))

}  // namespace fold_detail
}  // namespace mjtouch
