#include "common/fft.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "common/fft_kernels.h"
#include "common/fft_layout.h"
#include "common/simd.h"

namespace mjtouch {
namespace {

constexpr double kPi = 3.14159265358979323846;

using fft_detail::Butterflies;
using fft_detail::Dft;
using fft_detail::FusedButterflies;
using fft_detail::Twiddle;

// The butterfly groups of a Stockham stage of radix R (span = Ns): group j
// reads elements j + r n/R (in_step apart) and writes (j / Ns) Ns R +
// (j mod Ns) + r Ns (out_step apart), with the twiddles of row j mod Ns.
// f(jm, in offset, out offset, in_step, out_step), inlined (into each
// target_clones clone of the stage).
template <int R, typename F>
inline __attribute__((always_inline)) void ForEachGroup(int n, int span, int in_stride,
                                                        int out_stride, F&& f) {
  const int m = n / R;
  const size_t in_step = static_cast<size_t>(m) * in_stride;
  const size_t out_step = static_cast<size_t>(span) * out_stride;
  for (int j = 0; j < m; ++j) {
    const int jm = j % span;
    const int dst = (j / span) * span * R + jm;
    f(jm, static_cast<size_t>(j) * in_stride, static_cast<size_t>(dst) * out_stride, in_step,
      out_step);
  }
}

// One Stockham stage (Govindaraju et al. 2008, mixed radix): reads element
// j + r n/R, twiddles by exp(-+2 pi i r (j mod Ns) / (Ns R)), does a radix-R
// DFT and writes element (j / Ns) Ns R + (j mod Ns) + r Ns. Output is in
// natural order after the last stage. Every loop over b is independent per
// lane (no reductions) and no FMA is formed (-ffp-contract=off), so
// vectorised and scalar code round alike.
// kOut: Butterflies' (a last stage whose outputs r >= kOut are not needed).
// kInPlace: a last stage (span n / R) run on its input (out == in, same
// stride): butterfly j reads and writes elements j + r n/R alike, so each
// reads its inputs before writing them, and none reads another's outputs.
template <int R, bool kInverse, typename T, int kOut = R, bool kInPlace = false>
MJTOUCH_TARGET_CLONES void Stage(int n, int span, const T* tw_re, const T* tw_im, const T* in_re,
                                 const T* in_im, int in_stride, T* out_re, T* out_im,
                                 int out_stride, int batch) {
  ForEachGroup<R>(n, span, in_stride, out_stride,
                  [&](int jm, size_t io, size_t oo, size_t in_step, size_t out_step)
                      __attribute__((always_inline)) {
                        T wr[R], wi[R];
                        for (int r = 0; r < R; ++r) {
                          wr[r] = tw_re[jm * R + r];
                          wi[r] = kInverse ? -tw_im[jm * R + r] : tw_im[jm * R + r];
                        }
                        const T* ir = kInPlace ? nullptr : in_re + io;
                        const T* ii = kInPlace ? nullptr : in_im + io;
                        if (jm != 0) {
                          Butterflies<R, kInverse, true, T, kOut, kInPlace>(
                              ir, ii, in_step, out_re + oo, out_im + oo, out_step, wr, wi, batch);
                        } else {
                          Butterflies<R, kInverse, false, T, kOut, kInPlace>(
                              ir, ii, in_step, out_re + oo, out_im + oo, out_step, wr, wi, batch);
                        }
                      });
}

// A fused stage (FusedButterflies): twa / twb, stages A's and B's tables.
template <int Ra, int Rb, bool kInverse, bool kInPlace, bool kHalfA, typename T>
MJTOUCH_TARGET_CLONES void FusedStage(int n, int span, const T* twa_re, const T* twa_im,
                                      const T* twb_re, const T* twb_im, const T* in_re,
                                      const T* in_im, int in_stride, T* out_re, T* out_im,
                                      int out_stride, int batch) {
  ForEachGroup<Ra * Rb>(
      n, span, in_stride, out_stride,
      [&](int jm, size_t io, size_t oo, size_t in_step,
          size_t out_step) __attribute__((always_inline)) {
        T wa_r[Ra], wa_i[Ra], wb_r[Ra][Rb], wb_i[Ra][Rb];
        for (int r = 0; r < Ra; ++r) {
          wa_r[r] = twa_re[jm * Ra + r];
          wa_i[r] = kInverse ? -twa_im[jm * Ra + r] : twa_im[jm * Ra + r];
          for (int q = 0; q < Rb; ++q) {
            const int e = (r * span + jm) * Rb + q;
            wb_r[r][q] = twb_re[e];
            wb_i[r][q] = kInverse ? -twb_im[e] : twb_im[e];
          }
        }
        const T* ir = kInPlace ? nullptr : in_re + io;
        const T* ii = kInPlace ? nullptr : in_im + io;
        if (jm != 0) {
          if constexpr (!kHalfA)
            FusedButterflies<Ra, Rb, kInverse, false, false, kInPlace>(
                ir, ii, in_step, out_re + oo, out_im + oo, out_step, wa_r, wa_i, wb_r, wb_i, batch);
        } else {
          FusedButterflies<Ra, Rb, kInverse, true, kHalfA, kInPlace>(
              ir, ii, in_step, out_re + oo, out_im + oo, out_step, wa_r, wa_i, wb_r, wb_i, batch);
        }
      });
}

// The fused pairs FftPlan makes: (2, 3) and (3, 3).
template <bool kInverse, bool kInPlace, bool kHalfA, typename T>
void RunFusedStage(int ra, int n, int span, const T* twa_re, const T* twa_im, const T* twb_re,
                   const T* twb_im, const T* ir, const T* ii, int is, T* orr, T* oi, int os,
                   int batch) {
  if (ra == 2) {
    FusedStage<2, 3, kInverse, kInPlace, kHalfA>(n, span, twa_re, twa_im, twb_re, twb_im, ir, ii,
                                                 is, orr, oi, os, batch);
  } else if constexpr (!kHalfA) {
    FusedStage<3, 3, kInverse, kInPlace, false>(n, span, twa_re, twa_im, twb_re, twb_im, ir, ii, is,
                                                orr, oi, os, batch);
  }
}

template <bool kInverse, bool kInPlace, typename T>
void RunStage(int radix, int n, int span, const T* twr, const T* twi, const T* ir, const T* ii,
              int is, T* orr, T* oi, int os, int batch) {
  switch (radix) {
    case 2:
      Stage<2, kInverse, T, 2, kInPlace>(n, span, twr, twi, ir, ii, is, orr, oi, os, batch);
      break;
    case 3:
      Stage<3, kInverse, T, 3, kInPlace>(n, span, twr, twi, ir, ii, is, orr, oi, os, batch);
      break;
    case 4:
      Stage<4, kInverse, T, 4, kInPlace>(n, span, twr, twi, ir, ii, is, orr, oi, os, batch);
      break;
    case 8:
      Stage<8, kInverse, T, 8, kInPlace>(n, span, twr, twi, ir, ii, is, orr, oi, os, batch);
      break;
    default:
      Stage<5, kInverse, T, 5, kInPlace>(n, span, twr, twi, ir, ii, is, orr, oi, os, batch);
      break;
  }
}

// A first (span 1, untwiddled) radix-4 stage whose inputs j + 2 n/4 and
// j + 3 n/4 are zero: the butterfly of Butterflies<4> with x2 = x3 = 0
// dropped, which rounds alike (x + 0 and x - 0 are x), reading half the data.
template <bool kInverse, typename T>
MJTOUCH_TARGET_CLONES void FirstStage4HalfInput(int n, const T* in_re, const T* in_im,
                                                int in_stride, T* out_re, T* out_im, int out_stride,
                                                int batch) {
  constexpr T sg = kInverse ? T(-1) : T(1);
  const int m = n / 4;
  const size_t in_step = static_cast<size_t>(m) * in_stride;
  const size_t os = static_cast<size_t>(out_stride);
  for (int j = 0; j < m; ++j) {
    const T* __restrict a_r = in_re + static_cast<size_t>(j) * in_stride;
    const T* __restrict a_i = in_im + static_cast<size_t>(j) * in_stride;
    const T* __restrict b_r = a_r + in_step;
    const T* __restrict b_i = a_i + in_step;
    T* __restrict o_r = out_re + static_cast<size_t>(4 * j) * os;
    T* __restrict o_i = out_im + static_cast<size_t>(4 * j) * os;
#pragma GCC ivdep
    for (int b = 0; b < batch; ++b) {
      const T x0r = a_r[b], x0i = a_i[b], x1r = b_r[b], x1i = b_i[b];
      o_r[b] = x0r + x1r;
      o_i[b] = x0i + x1i;
      o_r[2 * os + b] = x0r - x1r;
      o_i[2 * os + b] = x0i - x1i;
      o_r[os + b] = x0r + sg * x1i;
      o_i[os + b] = x0i - sg * x1r;
      o_r[3 * os + b] = x0r - sg * x1i;
      o_i[3 * os + b] = x0i + sg * x1r;
    }
  }
}

// FirstStage4HalfInput followed by a radix-8 stage (span 4) as one radix-32
// stage: a pass over the data less, the same operations (the same bits).
// B butterfly r (< 4) takes output r of the eight half radix-4 butterflies,
// recomputed from their two inputs (loads from L1) rather than held: 32
// intermediates per lane would not fit in the registers.
template <int r, bool kInverse, typename T>
inline __attribute__((always_inline)) void Half4Then8(const T* __restrict a_r,
                                                      const T* __restrict a_i, size_t in_step,
                                                      T* __restrict o_r, T* __restrict o_i,
                                                      size_t os, const T (&wb_r)[4][8],
                                                      const T (&wb_i)[4][8], int batch) {
  constexpr T sg = kInverse ? T(-1) : T(1);
  T w_r[8], w_i[8];
  for (int q = 0; q < 8; ++q) {
    w_r[q] = wb_r[r][q];
    w_i[q] = wb_i[r][q];
  }
#pragma GCC ivdep
  for (int b = 0; b < batch; ++b) {
    T xr[8], xi[8], yr[8], yi[8];
    for (int q = 0; q < 8; ++q) {
      const T x0r = a_r[q * in_step + b], x0i = a_i[q * in_step + b];
      const T x1r = a_r[(q + 8) * in_step + b], x1i = a_i[(q + 8) * in_step + b];
      T hr, hi;  // FirstStage4HalfInput's output r
      if constexpr (r == 0) {
        hr = x0r + x1r;
        hi = x0i + x1i;
      } else if constexpr (r == 2) {
        hr = x0r - x1r;
        hi = x0i - x1i;
      } else if constexpr (r == 1) {
        hr = x0r + sg * x1i;
        hi = x0i - sg * x1r;
      } else {
        hr = x0r - sg * x1i;
        hi = x0i + sg * x1r;
      }
      if (r == 0 || q == 0) {
        xr[q] = hr;
        xi[q] = hi;
      } else {
        Twiddle(hr, hi, w_r[q], w_i[q], &xr[q], &xi[q]);
      }
    }
    Dft<8, kInverse, T>(xr, xi, yr, yi);
    for (int u = 0; u < 8; ++u) {
      o_r[(r + 4 * u) * os + b] = yr[u];
      o_i[(r + 4 * u) * os + b] = yi[u];
    }
  }
}

template <bool kInverse, typename T>
MJTOUCH_TARGET_CLONES void FirstStages4Half8(int n, const T* tw8_re, const T* tw8_im,
                                             const T* in_re, const T* in_im, int in_stride,
                                             T* out_re, T* out_im, int out_stride, int batch) {
  const int m = n / 32;
  const size_t in_step = static_cast<size_t>(m) * in_stride;
  const size_t os = static_cast<size_t>(out_stride);
  T wb_r[4][8], wb_i[4][8];  // stage B's rows jm = r
  for (int r = 0; r < 4; ++r)
    for (int q = 0; q < 8; ++q) {
      wb_r[r][q] = tw8_re[r * 8 + q];
      wb_i[r][q] = kInverse ? -tw8_im[r * 8 + q] : tw8_im[r * 8 + q];
    }
  for (int j = 0; j < m; ++j) {
    const T* a_r = in_re + static_cast<size_t>(j) * in_stride;
    const T* a_i = in_im + static_cast<size_t>(j) * in_stride;
    T* o_r = out_re + static_cast<size_t>(32 * j) * os;
    T* o_i = out_im + static_cast<size_t>(32 * j) * os;
    Half4Then8<0, kInverse>(a_r, a_i, in_step, o_r, o_i, os, wb_r, wb_i, batch);
    Half4Then8<1, kInverse>(a_r, a_i, in_step, o_r, o_i, os, wb_r, wb_i, batch);
    Half4Then8<2, kInverse>(a_r, a_i, in_step, o_r, o_i, os, wb_r, wb_i, batch);
    Half4Then8<3, kInverse>(a_r, a_i, in_step, o_r, o_i, os, wb_r, wb_i, batch);
  }
}

// A first (span 1, untwiddled) stage whose inputs are first multiplied by
// the real factors k[e * ks + b] (element e, lane b): the product of a
// spectrum with a kernel's fused into the inverse transform's first pass,
// the same products (the same bits) as multiplying beforehand.
template <int R, bool kInverse, typename T>
MJTOUCH_TARGET_CLONES void FirstStageScaled(int n, const T* k, int ks, const T* in_re,
                                            const T* in_im, int in_stride, T* out_re, T* out_im,
                                            int out_stride, int batch) {
  const int m = n / R;
  const size_t in_step = static_cast<size_t>(m) * in_stride;
  const size_t k_step = static_cast<size_t>(m) * ks;
  const T w[R] = {};
  for (int j = 0; j < m; ++j) {
    const size_t io = static_cast<size_t>(j) * in_stride;
    const size_t oo = static_cast<size_t>(j) * R * out_stride;
    Butterflies<R, kInverse, false, T, R, false, true>(in_re + io, in_im + io, in_step, out_re + oo,
                                                       out_im + oo, out_stride, w, w, batch,
                                                       k + static_cast<size_t>(j) * ks, k_step);
  }
}

template <bool kInverse, typename T>
void RunFirstStageScaled(int radix, int n, const T* k, int ks, const T* ir, const T* ii, int is,
                         T* orr, T* oi, int os, int batch) {
  switch (radix) {
    case 2: FirstStageScaled<2, kInverse>(n, k, ks, ir, ii, is, orr, oi, os, batch); break;
    case 3: FirstStageScaled<3, kInverse>(n, k, ks, ir, ii, is, orr, oi, os, batch); break;
    case 4: FirstStageScaled<4, kInverse>(n, k, ks, ir, ii, is, orr, oi, os, batch); break;
    case 8: FirstStageScaled<8, kInverse>(n, k, ks, ir, ii, is, orr, oi, os, batch); break;
    default: FirstStageScaled<5, kInverse>(n, k, ks, ir, ii, is, orr, oi, os, batch); break;
  }
}

// A last stage writing outputs r < kOut only: radix 5 the first three,
// radix 3 the first two.
template <bool kInverse, bool kInPlace, typename T>
void RunLastStagePart(int radix, int n, int span, const T* twr, const T* twi, const T* ir,
                      const T* ii, int is, T* orr, T* oi, int os, int batch) {
  if (radix == 5) {
    Stage<5, kInverse, T, 3, kInPlace>(n, span, twr, twi, ir, ii, is, orr, oi, os, batch);
  } else {
    Stage<3, kInverse, T, 2, kInPlace>(n, span, twr, twi, ir, ii, is, orr, oi, os, batch);
  }
}

// A first (span 1) radix-2 stage whose inputs j + n/2 are zero: both
// outputs are x_j (x + 0 and x - 0 are x).
template <typename T>
void FirstStage2HalfInput(int n, const T* in_re, const T* in_im, int in_stride, T* out_re,
                          T* out_im, int out_stride, int batch) {
  const size_t os = static_cast<size_t>(out_stride);
  for (int j = 0; j < n / 2; ++j) {
    const T* a_r = in_re + static_cast<size_t>(j) * in_stride;
    const T* a_i = in_im + static_cast<size_t>(j) * in_stride;
    T* o_r = out_re + static_cast<size_t>(2 * j) * os;
    T* o_i = out_im + static_cast<size_t>(2 * j) * os;
    std::memcpy(o_r, a_r, batch * sizeof(T));
    std::memcpy(o_r + os, a_r, batch * sizeof(T));
    std::memcpy(o_i, a_i, batch * sizeof(T));
    std::memcpy(o_i + os, a_i, batch * sizeof(T));
  }
}

// dst[r * dst_stride + c] = src[r * src_stride + c], r < rows, c < cols.
template <typename T>
inline void CopyRows(const T* src, size_t src_stride, int rows, int cols, T* dst,
                     size_t dst_stride) {
  for (int r = 0; r < rows; ++r)
    std::memcpy(dst + r * dst_stride, src + r * src_stride, cols * sizeof(T));
}

// dst[c * dst_stride + r] = src[r * src_stride + c], r < rows, c < cols.
void Transpose(const double* src, int src_stride, int rows, int cols, double* dst, int dst_stride) {
  constexpr int kBlock = 32;
  for (int r0 = 0; r0 < rows; r0 += kBlock) {
    const int r1 = std::min(rows, r0 + kBlock);
    for (int c0 = 0; c0 < cols; c0 += kBlock) {
      const int c1 = std::min(cols, c0 + kBlock);
      for (int r = r0; r < r1; ++r)
        for (int c = c0; c < c1; ++c)
          dst[static_cast<size_t>(c) * dst_stride + r] =
              src[static_cast<size_t>(r) * src_stride + c];
    }
  }
}

}  // namespace

bool IsFftSize(int n) {
  if (n < 1) return false;
  for (int p : {2, 3, 5})
    while (n % p == 0) n /= p;
  return n == 1;
}

int NextFftSize(int n) {
  int m = std::max(n, 1);
  while (!IsFftSize(m)) ++m;
  return m;
}

FftPlan::FftPlan(int n) : n_(n) {
  std::vector<int> radices;
  int rest = n;
  // Powers of two as radix-4 stages; an odd power from 2^5 on ends them
  // with one radix-8 stage rather than a radix-2 one (a pass over the data
  // less; the first stage stays radix 4 for Transform's half-input skip).
  // Measured: ConvolveReal<float> 160 x 160 0.94x, 160 x 150 0.97x time.
  int p2 = 0;
  while (rest % 2 == 0) {
    rest /= 2;
    ++p2;
  }
  if (p2 >= 5 && p2 % 2 == 1) {
    for (int k = 0; k < (p2 - 3) / 2; ++k) radices.push_back(4);
    radices.push_back(8);
    p2 = 0;
  }
  for (; p2 >= 2; p2 -= 2) radices.push_back(4);
  if (p2 == 1) radices.push_back(2);
  while (rest % 3 == 0) {
    radices.push_back(3);
    rest /= 3;
  }
  while (rest % 5 == 0) {
    radices.push_back(5);
    rest /= 5;
  }
  int span = 1;
  for (int R : radices) {
    Stage s;
    s.radix = R;
    s.span = span;
    s.tw_re.resize(static_cast<size_t>(span) * R);
    s.tw_im.resize(static_cast<size_t>(span) * R);
    for (int j = 0; j < span; ++j)
      for (int r = 0; r < R; ++r) {
        const double a = -2.0 * kPi * r * j / (static_cast<double>(span) * R);
        s.tw_re[j * R + r] = std::cos(a);
        s.tw_im[j * R + r] = std::sin(a);
      }
    s.tw_re_f.assign(s.tw_re.begin(), s.tw_re.end());
    s.tw_im_f.assign(s.tw_im.begin(), s.tw_im.end());
    span *= R;
    // Radix 3 after a 2 or a 3: the two run as one stage (FusedStage), a
    // pass over the data less with the same bits. Measured (ConvolveReal
    // <float>, threads 1, against unfused): 180 x 150 0.82x, 160 x 150
    // 0.91x the time. (5 x 5 fused: 1.4x, its 50 values per lane spill.)
    Stage* prev = stages_.empty() ? nullptr : &stages_.back();
    if (R == 3 && prev && prev->ra == 0 && (prev->radix == 2 || prev->radix == 3)) {
      prev->ra = prev->radix;
      prev->radix *= R;
      prev->tw2_re = std::move(s.tw_re);
      prev->tw2_im = std::move(s.tw_im);
      prev->tw2_re_f = std::move(s.tw_re_f);
      prev->tw2_im_f = std::move(s.tw_im_f);
      continue;
    }
    stages_.push_back(std::move(s));
  }
}

namespace {

// f(flag) with the flag as a compile-time constant (std::bool_constant), so
// one call site picks among a kernel's template instances.
template <typename F>
inline void WithFlag(bool flag, F&& f) {
  if (flag) {
    f(std::true_type{});
  } else {
    f(std::false_type{});
  }
}
template <typename F>
inline void WithFlags(bool a, bool b, F&& f) {
  WithFlag(a, [&](auto x) { WithFlag(b, [&](auto y) { f(x, y); }); });
}

// A stage's twiddle table in the transform's precision.
template <typename T>
const T* Tables(const std::vector<double>& d, const std::vector<float>& f) {
  if constexpr (std::is_same_v<T, float>) {
    return f.data();
  } else {
    return d.data();
  }
}

}  // namespace

template <typename T>
void FftPlan::Transform(T* re, T* im, int batch, int stride, bool inverse, T* sre, T* sim,
                        int nonzero, int needed, const T* scale, int scale_stride) const {
  const bool half_input = SkipsUpperHalf(nonzero);
  // The scale fused into the first stage when that is a generic one (not
  // half-input, not in place); otherwise multiplied beforehand.
  const bool scale_first = scale && !half_input && stages_.size() > 1 && stages_[0].ra == 0;
  if (scale && !scale_first) {
    for (int e = 0; e < n_; ++e)
      for (int b = 0; b < batch; ++b) {
        re[static_cast<size_t>(e) * stride + b] *= scale[static_cast<size_t>(e) * scale_stride + b];
        im[static_cast<size_t>(e) * stride + b] *= scale[static_cast<size_t>(e) * scale_stride + b];
      }
  }
  // A last radix-R stage writes element j + r n/R from output r: with
  // needed <= 3 n / 5 (R = 5) or 2 n / 3 (R = 3), outputs 3-4 or 2 are
  // never read.
  const int last_radix = stages_.empty() ? 0 : stages_.back().radix;
  const bool last_part =
      needed >= 0 && stages_.size() > 1 && stages_.back().ra == 0 &&
      ((last_radix == 5 && 5 * needed <= 3 * n_) || (last_radix == 3 && 3 * needed <= 2 * n_));
  // Ping-pong between the data (row stride `stride`) and the scratch (row
  // stride `batch` rounded up to whole 32-byte vectors).
  constexpr int kVec = 32 / sizeof(T);
  const int scratch_stride = (batch + kVec - 1) / kVec * kVec;
  const T* ir = re;
  const T* ii = im;
  int is = stride;
  bool in_data = true;
  // A half-input radix-4 first stage and a radix-8 second run as one
  // (FirstStages4Half8). Measured: ConvolveReal<float> 160 x 150 and
  // 160 x 160 0.97-0.98x (the fused stage half the two's time, but the
  // radix-5 stage after it no longer runs in place).
  const bool half_4_8 = half_input && stages_.size() > 1 && stages_[0].radix == 4 &&
                        stages_[1].radix == 8 && stages_[1].ra == 0;
  for (const Stage& s : stages_) {
    if (half_4_8 && &s == &stages_[1]) continue;
    // An odd number of stages: the last runs in place on the data (Stage's
    // kInPlace) rather than into the scratch and back (a pass less).
    const bool in_place = in_data && stages_.size() > 1u + half_4_8 && &s == &stages_.back();
    T* orr = in_data && !in_place ? sre : re;
    T* oi = in_data && !in_place ? sim : im;
    const int os = in_data && !in_place ? scratch_stride : stride;
    const T* twr = Tables<T>(s.tw_re, s.tw_re_f);
    const T* twi = Tables<T>(s.tw_im, s.tw_im_f);
    const bool first = &s == &stages_[0];
    if (half_4_8 && first) {
      const Stage& s8 = stages_[1];
      WithFlag(inverse, [&](auto inv) {
        FirstStages4Half8<inv>(n_, Tables<T>(s8.tw_re, s8.tw_re_f), Tables<T>(s8.tw_im, s8.tw_im_f),
                               ir, ii, is, orr, oi, os, batch);
      });
    } else if (s.ra != 0) {
      const T* tw2r = Tables<T>(s.tw2_re, s.tw2_re_f);
      const T* tw2i = Tables<T>(s.tw2_im, s.tw2_im_f);
      const bool half = half_input && first;  // (ra 2: SkipsUpperHalf)
      WithFlags(inverse, in_place, [&](auto inv, auto ip) {
        if (half) {
          RunFusedStage<inv, false, true>(s.ra, n_, s.span, twr, twi, tw2r, tw2i, ir, ii, is, orr,
                                          oi, os, batch);
        } else {
          RunFusedStage<inv, ip, false>(s.ra, n_, s.span, twr, twi, tw2r, tw2i, ir, ii, is, orr, oi,
                                        os, batch);
        }
      });
    } else if (last_part && &s == &stages_.back()) {
      WithFlags(inverse, in_place, [&](auto inv, auto ip) {
        RunLastStagePart<inv, ip>(s.radix, n_, s.span, twr, twi, ir, ii, is, orr, oi, os, batch);
      });
    } else if (scale_first && first) {
      WithFlag(inverse, [&](auto inv) {
        RunFirstStageScaled<inv>(s.radix, n_, scale, scale_stride, ir, ii, is, orr, oi, os, batch);
      });
    } else if (half_input && first && s.radix == 2) {
      FirstStage2HalfInput(n_, ir, ii, is, orr, oi, os, batch);
    } else if (half_input && first) {
      WithFlag(inverse,
               [&](auto inv) { FirstStage4HalfInput<inv>(n_, ir, ii, is, orr, oi, os, batch); });
    } else {
      WithFlags(inverse, in_place, [&](auto inv, auto ip) {
        RunStage<inv, ip>(s.radix, n_, s.span, twr, twi, ir, ii, is, orr, oi, os, batch);
      });
    }
    ir = orr;
    ii = oi;
    is = os;
    in_data = in_place || !in_data;
  }
  if (!in_data) {
    // (a single stage only: longer plans end in the data)
    const int rows = last_part ? needed : n_;
    CopyRows(sre, scratch_stride, rows, batch, re, stride);
    CopyRows(sim, scratch_stride, rows, batch, im, stride);
  }
}
template void FftPlan::Transform(double*, double*, int, int, bool, double*, double*, int, int,
                                 const double*, int) const;
template void FftPlan::Transform(float*, float*, int, int, bool, float*, float*, int, int,
                                 const float*, int) const;

using fft_detail::PaddedStride;
using fft_detail::SplitScratch;

Fft2D::Fft2D(int nx, int ny) : nx_(nx), ny_(ny), spec_stride_(PaddedStride(ny)), px_(nx), py_(ny) {}

void Fft2D::Forward(const double* re, const double* im, int stride, int rows, int cols,
                    double* spec_re, double* spec_im, std::vector<double>* scratch) const {
  const int lw = PaddedStride(cols);
  const size_t W = static_cast<size_t>(ny_) * lw;
  double *wr, *wi, *sr, *si;
  SplitScratch(W, spectrum_size(), scratch, &wr, &wi, &sr, &si);
  // Along y, the `cols` nonzero columns only (ny x cols).
  std::fill(wr, wr + W, 0.0);
  std::fill(wi, wi + W, 0.0);
  CopyRows(re, stride, rows, cols, wr, lw);
  if (im) CopyRows(im, stride, rows, cols, wi, lw);
  py_.Transform(wr, wi, cols, lw, false, sr, si);
  // Transpose to (x, ky); zero columns stay zero.
  const int ls = spec_stride_;
  Transpose(wr, lw, ny_, cols, spec_re, ls);
  Transpose(wi, lw, ny_, cols, spec_im, ls);
  std::fill(spec_re + static_cast<size_t>(cols) * ls, spec_re + spectrum_size(), 0.0);
  std::fill(spec_im + static_cast<size_t>(cols) * ls, spec_im + spectrum_size(), 0.0);
  px_.Transform(spec_re, spec_im, ny_, ls, false, sr, si);
}

void Fft2D::Inverse(double* spec_re, double* spec_im, int rows, int cols, double* re, double* im,
                    int stride, std::vector<double>* scratch) const {
  const int lw = PaddedStride(cols);
  const size_t W = static_cast<size_t>(ny_) * lw;
  double *wr, *wi, *sr, *si;
  SplitScratch(W, spectrum_size(), scratch, &wr, &wi, &sr, &si);
  const int ls = spec_stride_;
  px_.Transform(spec_re, spec_im, ny_, ls, true, sr, si);
  Transpose(spec_re, ls, cols, ny_, wr, lw);
  Transpose(spec_im, ls, cols, ny_, wi, lw);
  py_.Transform(wr, wi, cols, lw, true, sr, si);
  CopyRows(wr, lw, rows, cols, re, stride);
  if (im) CopyRows(wi, lw, rows, cols, im, stride);
}

}  // namespace mjtouch
