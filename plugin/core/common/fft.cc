#include "common/fft.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "common/simd.h"
#include "common/thread_pool.h"

namespace mjtouch {
namespace {

constexpr double kPi = 3.14159265358979323846;

// One Stockham stage (Govindaraju et al. 2008, mixed radix): reads element
// j + r n/R, twiddles by exp(-+2 pi i r (j mod Ns) / (Ns R)), does a radix-R
// DFT and writes element (j / Ns) Ns R + (j mod Ns) + r Ns. Output is in
// natural order after the last stage. Every loop over b is independent per
// lane (no reductions), so vectorised and scalar code round alike.
// The butterflies of one j over lanes [0, batch). kTwiddle: multiply the
// inputs r >= 1 by w[r] first. Pointers are restrict-qualified and the
// lanes independent, so the loop vectorises (no gathers, no branches).
// kOut (radix 5: 3 or 5; radix 3: 2 or 3): the outputs r < kOut only.
// kInPlace: read the inputs from out_re / out_im (in_re / in_im unused), the
// elements each butterfly writes being the ones it reads (a last stage).
// kScale: the inputs times a real factor first (k[r * k_step + b]).
template <int R, bool kInverse, bool kTwiddle, typename T, int kOut = R, bool kInPlace = false,
          bool kScale = false>
inline __attribute__((always_inline)) void Butterflies(
    const T* __restrict in_re_arg, const T* __restrict in_im_arg, size_t in_step_arg,
    T* __restrict out_re, T* __restrict out_im, size_t out_step, const T* wr, const T* wi,
    int batch, const T* __restrict k = nullptr, size_t k_step = 0) {
  const T* in_re = kInPlace ? out_re : in_re_arg;
  const T* in_im = kInPlace ? out_im : in_im_arg;
  const size_t in_step = kInPlace ? out_step : in_step_arg;
  constexpr T sg = kInverse ? T(-1) : T(1);
  const T c3 = T(-0.5), s3 = T(0.86602540378443864676);
  const T c51 = T(0.30901699437494742410), c52 = T(-0.80901699437494742410);
  const T s51 = T(0.95105651629515357212), s52 = T(0.58778525229247312917);
  T w_r[R], w_i[R];
  for (int r = 0; r < R; ++r) {
    w_r[r] = wr[r];
    w_i[r] = wi[r];
  }
#pragma GCC ivdep
  for (int b = 0; b < batch; ++b) {
    T xr[R], xi[R];
    xr[0] = kScale ? in_re[b] * k[b] : in_re[b];
    xi[0] = kScale ? in_im[b] * k[b] : in_im[b];
    for (int r = 1; r < R; ++r) {
      T a = in_re[r * in_step + b], c = in_im[r * in_step + b];
      if constexpr (kScale) {
        a = a * k[r * k_step + b];
        c = c * k[r * k_step + b];
      }
      if constexpr (kTwiddle) {
        xr[r] = a * w_r[r] - c * w_i[r];
        xi[r] = a * w_i[r] + c * w_r[r];
      } else {
        xr[r] = a;
        xi[r] = c;
      }
    }
    T* orr = out_re + b;
    T* oi = out_im + b;
    if constexpr (R == 2) {
      orr[0] = xr[0] + xr[1];
      oi[0] = xi[0] + xi[1];
      orr[out_step] = xr[0] - xr[1];
      oi[out_step] = xi[0] - xi[1];
    } else if constexpr (R == 3) {
      const T tr = xr[1] + xr[2], ti = xi[1] + xi[2];
      const T mr = xr[0] + c3 * tr, mi = xi[0] + c3 * ti;
      const T dr = s3 * (xr[1] - xr[2]), di = s3 * (xi[1] - xi[2]);
      orr[0] = xr[0] + tr;
      oi[0] = xi[0] + ti;
      orr[out_step] = mr + sg * di;
      oi[out_step] = mi - sg * dr;
      if constexpr (kOut == 3) {
        orr[2 * out_step] = mr - sg * di;
        oi[2 * out_step] = mi + sg * dr;
      }
    } else if constexpr (R == 4) {
      const T t0r = xr[0] + xr[2], t0i = xi[0] + xi[2];
      const T t1r = xr[0] - xr[2], t1i = xi[0] - xi[2];
      const T t2r = xr[1] + xr[3], t2i = xi[1] + xi[3];
      const T t3r = xr[1] - xr[3], t3i = xi[1] - xi[3];
      orr[0] = t0r + t2r;
      oi[0] = t0i + t2i;
      orr[2 * out_step] = t0r - t2r;
      oi[2 * out_step] = t0i - t2i;
      orr[out_step] = t1r + sg * t3i;
      oi[out_step] = t1i - sg * t3r;
      orr[3 * out_step] = t1r - sg * t3i;
      oi[3 * out_step] = t1i + sg * t3r;
    } else if constexpr (R == 8) {
      // Even and odd halves as radix-4 DFTs, the odd one times w8^k
      // (w8 = exp(-+ 2 pi i / 8): multiples of (1 -+ i) / sqrt 2, -+i).
      const T r2 = T(0.70710678118654752440);
      T er[4], ei[4], pr[4], pi[4];
      for (int q = 0; q < 2; ++q) {
        const T a0r = xr[q], a0i = xi[q], a1r = xr[q + 2], a1i = xi[q + 2];
        const T a2r = xr[q + 4], a2i = xi[q + 4], a3r = xr[q + 6], a3i = xi[q + 6];
        const T t0r = a0r + a2r, t0i = a0i + a2i, t1r = a0r - a2r, t1i = a0i - a2i;
        const T t2r = a1r + a3r, t2i = a1i + a3i, t3r = a1r - a3r, t3i = a1i - a3i;
        T* yr = q == 0 ? er : pr;
        T* yi = q == 0 ? ei : pi;
        yr[0] = t0r + t2r;
        yi[0] = t0i + t2i;
        yr[2] = t0r - t2r;
        yi[2] = t0i - t2i;
        yr[1] = t1r + sg * t3i;
        yi[1] = t1i - sg * t3r;
        yr[3] = t1r - sg * t3i;
        yi[3] = t1i + sg * t3r;
      }
      const T o1r = (pr[1] + sg * pi[1]) * r2, o1i = (pi[1] - sg * pr[1]) * r2;
      const T o2r = sg * pi[2], o2i = -sg * pr[2];
      const T o3r = (sg * pi[3] - pr[3]) * r2, o3i = (-sg * pr[3] - pi[3]) * r2;
      const T qr[4] = {pr[0], o1r, o2r, o3r}, qi[4] = {pi[0], o1i, o2i, o3i};
      for (int k = 0; k < 4; ++k) {
        orr[k * out_step] = er[k] + qr[k];
        oi[k * out_step] = ei[k] + qi[k];
        orr[(k + 4) * out_step] = er[k] - qr[k];
        oi[(k + 4) * out_step] = ei[k] - qi[k];
      }
    } else {
      static_assert(R == 5, "radix");
      static_assert(kOut == 5 || kOut == 3, "outputs");
      const T t1r = xr[1] + xr[4], t1i = xi[1] + xi[4];
      const T t2r = xr[2] + xr[3], t2i = xi[2] + xi[3];
      const T d1r = xr[1] - xr[4], d1i = xi[1] - xi[4];
      const T d2r = xr[2] - xr[3], d2i = xi[2] - xi[3];
      const T m1r = xr[0] + c51 * t1r + c52 * t2r, m1i = xi[0] + c51 * t1i + c52 * t2i;
      const T m2r = xr[0] + c52 * t1r + c51 * t2r, m2i = xi[0] + c52 * t1i + c51 * t2i;
      const T e1r = s51 * d1r + s52 * d2r, e1i = s51 * d1i + s52 * d2i;
      const T e2r = s52 * d1r - s51 * d2r, e2i = s52 * d1i - s51 * d2i;
      orr[0] = xr[0] + t1r + t2r;
      oi[0] = xi[0] + t1i + t2i;
      orr[out_step] = m1r + sg * e1i;
      oi[out_step] = m1i - sg * e1r;
      orr[2 * out_step] = m2r + sg * e2i;
      oi[2 * out_step] = m2i - sg * e2r;
      if constexpr (kOut == 5) {
        orr[4 * out_step] = m1r - sg * e1i;
        oi[4 * out_step] = m1i + sg * e1r;
        orr[3 * out_step] = m2r - sg * e2i;
        oi[3 * out_step] = m2i + sg * e2r;
      }
    }
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
MJTOUCH_TARGET_CLONES
void Stage(int n, int span, const T* tw_re, const T* tw_im, const T* in_re, const T* in_im,
           int in_stride, T* out_re, T* out_im, int out_stride, int batch) {
  const int m = n / R;
  const size_t in_step = static_cast<size_t>(m) * in_stride;
  const size_t out_step = static_cast<size_t>(span) * out_stride;
  for (int j = 0; j < m; ++j) {
    const int jm = j % span;
    const int dst = (j / span) * span * R + jm;
    T wr[R], wi[R];
    for (int r = 0; r < R; ++r) {
      wr[r] = tw_re[jm * R + r];
      wi[r] = kInverse ? -tw_im[jm * R + r] : tw_im[jm * R + r];
    }
    const size_t io = static_cast<size_t>(j) * in_stride;
    const size_t oo = static_cast<size_t>(dst) * out_stride;
    const T* ir = kInPlace ? nullptr : in_re + io;
    const T* ii = kInPlace ? nullptr : in_im + io;
    if (jm != 0) {
      Butterflies<R, kInverse, true, T, kOut, kInPlace>(ir, ii, in_step, out_re + oo,
                                                        out_im + oo, out_step, wr, wi, batch);
    } else {
      Butterflies<R, kInverse, false, T, kOut, kInPlace>(ir, ii, in_step, out_re + oo,
                                                         out_im + oo, out_step, wr, wi, batch);
    }
  }
}

template <bool kInverse, bool kInPlace, typename T>
void RunStage(int radix, int n, int span, const T* twr, const T* twi, const T* ir,
              const T* ii, int is, T* orr, T* oi, int os, int batch) {
  switch (radix) {
    case 2: Stage<2, kInverse, T, 2, kInPlace>(n, span, twr, twi, ir, ii, is, orr, oi, os, batch); break;
    case 3: Stage<3, kInverse, T, 3, kInPlace>(n, span, twr, twi, ir, ii, is, orr, oi, os, batch); break;
    case 4: Stage<4, kInverse, T, 4, kInPlace>(n, span, twr, twi, ir, ii, is, orr, oi, os, batch); break;
    case 8: Stage<8, kInverse, T, 8, kInPlace>(n, span, twr, twi, ir, ii, is, orr, oi, os, batch); break;
    default: Stage<5, kInverse, T, 5, kInPlace>(n, span, twr, twi, ir, ii, is, orr, oi, os, batch); break;
  }
}

// A first (span 1, untwiddled) radix-4 stage whose inputs j + 2 n/4 and
// j + 3 n/4 are zero: the butterfly of Butterflies<4> with x2 = x3 = 0
// dropped, which rounds alike (x + 0 and x - 0 are x), reading half the data.
template <bool kInverse, typename T>
MJTOUCH_TARGET_CLONES
void FirstStage4HalfInput(int n, const T* in_re, const T* in_im, int in_stride, T* out_re,
                          T* out_im, int out_stride, int batch) {
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

// A first (span 1, untwiddled) stage whose inputs are first multiplied by
// the real factors k[e * ks + b] (element e, lane b): the product of a
// spectrum with a kernel's fused into the inverse transform's first pass,
// the same products (the same bits) as multiplying beforehand.
template <int R, bool kInverse, typename T>
MJTOUCH_TARGET_CLONES
void FirstStageScaled(int n, const T* k, int ks, const T* in_re, const T* in_im, int in_stride,
                      T* out_re, T* out_im, int out_stride, int batch) {
  const int m = n / R;
  const size_t in_step = static_cast<size_t>(m) * in_stride;
  const size_t k_step = static_cast<size_t>(m) * ks;
  const T w[R] = {};
  for (int j = 0; j < m; ++j) {
    const size_t io = static_cast<size_t>(j) * in_stride;
    const size_t oo = static_cast<size_t>(j) * R * out_stride;
    Butterflies<R, kInverse, false, T, R, false, true>(in_re + io, in_im + io, in_step,
                                                       out_re + oo, out_im + oo, out_stride, w,
                                                       w, batch, k + static_cast<size_t>(j) * ks,
                                                       k_step);
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
void Transpose(const double* src, int src_stride, int rows, int cols, double* dst,
               int dst_stride) {
  constexpr int kBlock = 32;
  for (int r0 = 0; r0 < rows; r0 += kBlock) {
    const int r1 = std::min(rows, r0 + kBlock);
    for (int c0 = 0; c0 < cols; c0 += kBlock) {
      const int c1 = std::min(cols, c0 + kBlock);
      for (int r = r0; r < r1; ++r)
        for (int c = c0; c < c1; ++c)
          dst[static_cast<size_t>(c) * dst_stride + r] = src[static_cast<size_t>(r) * src_stride + c];
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
  while (rest % 2 == 0) { rest /= 2; ++p2; }
  if (p2 >= 5 && p2 % 2 == 1) {
    for (int k = 0; k < (p2 - 3) / 2; ++k) radices.push_back(4);
    radices.push_back(8);
    p2 = 0;
  }
  for (; p2 >= 2; p2 -= 2) radices.push_back(4);
  if (p2 == 1) radices.push_back(2);
  while (rest % 3 == 0) { radices.push_back(3); rest /= 3; }
  while (rest % 5 == 0) { radices.push_back(5); rest /= 5; }
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
    stages_.push_back(std::move(s));
    span *= R;
  }
}

template <typename T>
void FftPlan::Transform(T* re, T* im, int batch, int stride, bool inverse, T* sre, T* sim,
                        int nonzero, int needed, const T* scale, int scale_stride) const {
  const bool half_input = SkipsUpperHalf(nonzero);
  // The scale fused into the first stage when that is a generic one (not
  // half-input, not in place); otherwise multiplied beforehand.
  const bool scale_first = scale && !half_input && stages_.size() > 1;
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
      needed >= 0 && stages_.size() > 1 &&
      ((last_radix == 5 && 5 * needed <= 3 * n_) || (last_radix == 3 && 3 * needed <= 2 * n_));
  // Ping-pong between the data (row stride `stride`) and the scratch (row
  // stride `batch` rounded up to whole 32-byte vectors).
  constexpr int kVec = 32 / sizeof(T);
  const int scratch_stride = (batch + kVec - 1) / kVec * kVec;
  const T* ir = re;
  const T* ii = im;
  int is = stride;
  bool in_data = true;
  for (const Stage& s : stages_) {
    // An odd number of stages: the last runs in place on the data (Stage's
    // kInPlace) rather than into the scratch and back (a pass less).
    const bool in_place = in_data && stages_.size() > 1 && &s == &stages_.back();
    T* orr = in_data && !in_place ? sre : re;
    T* oi = in_data && !in_place ? sim : im;
    const int os = in_data && !in_place ? scratch_stride : stride;
    const T* twr;
    const T* twi;
    if constexpr (std::is_same_v<T, float>) {
      twr = s.tw_re_f.data();
      twi = s.tw_im_f.data();
    } else {
      twr = s.tw_re.data();
      twi = s.tw_im.data();
    }
    if (last_part && &s == &stages_.back()) {
      if (in_place) {
        if (inverse) {
          RunLastStagePart<true, true>(s.radix, n_, s.span, twr, twi, ir, ii, is, orr, oi, os, batch);
        } else {
          RunLastStagePart<false, true>(s.radix, n_, s.span, twr, twi, ir, ii, is, orr, oi, os, batch);
        }
      } else if (inverse) {
        RunLastStagePart<true, false>(s.radix, n_, s.span, twr, twi, ir, ii, is, orr, oi, os, batch);
      } else {
        RunLastStagePart<false, false>(s.radix, n_, s.span, twr, twi, ir, ii, is, orr, oi, os, batch);
      }
    } else if (scale_first && &s == &stages_[0]) {
      if (inverse) {
        RunFirstStageScaled<true>(s.radix, n_, scale, scale_stride, ir, ii, is, orr, oi, os, batch);
      } else {
        RunFirstStageScaled<false>(s.radix, n_, scale, scale_stride, ir, ii, is, orr, oi, os, batch);
      }
    } else if (half_input && &s == &stages_[0] && s.radix == 2) {
      FirstStage2HalfInput(n_, ir, ii, is, orr, oi, os, batch);
    } else if (half_input && &s == &stages_[0]) {
      if (inverse) {
        FirstStage4HalfInput<true>(n_, ir, ii, is, orr, oi, os, batch);
      } else {
        FirstStage4HalfInput<false>(n_, ir, ii, is, orr, oi, os, batch);
      }
    } else if (in_place) {
      if (inverse) {
        RunStage<true, true>(s.radix, n_, s.span, twr, twi, ir, ii, is, orr, oi, os, batch);
      } else {
        RunStage<false, true>(s.radix, n_, s.span, twr, twi, ir, ii, is, orr, oi, os, batch);
      }
    } else if (inverse) {
      RunStage<true, false>(s.radix, n_, s.span, twr, twi, ir, ii, is, orr, oi, os, batch);
    } else {
      RunStage<false, false>(s.radix, n_, s.span, twr, twi, ir, ii, is, orr, oi, os, batch);
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
template void FftPlan::Transform(double*, double*, int, int, bool, double*, double*, int,
                                 int, const double*, int) const;
template void FftPlan::Transform(float*, float*, int, int, bool, float*, float*, int, int,
                                 const float*, int) const;

namespace {
// Row strides an odd multiple of 8 elements: not a power of two (those put
// the radix streams of a stage in the same cache sets, measured 3-8x slower
// at 128 and 256), and whole 32-byte vectors, so that with SplitScratch's
// aligned arrays rows start on a vector boundary (unaligned rows cross a
// cache line every other load: measured 7-8% of ConvolveReal<float>).
int PaddedStride(int n) {
  int r = (n + 7) / 8 * 8;
  if ((r / 8) % 2 == 0) r += 8;
  return r;
}

// dst[c * ds + r] = src[r * ss + c], r < rows, c < cols: 8 x 8 (float) or
// 4 x 4 (double) blocks transposed in registers (GCC vector extensions:
// AVX2 or SSE2 pairs, no intrinsics), the edges one by one. Data movement
// only: the same bits on every path.
typedef float V8f __attribute__((vector_size(32)));
typedef double V4d __attribute__((vector_size(32)));
// Macros, not functions: 32-byte vectors passed by value warn of an ABI
// change (-Wpsabi) in the SSE2 build.
#define MJTOUCH_LOAD(v, p) std::memcpy(&(v), (p), sizeof(v))
#define MJTOUCH_STORE(p, v)       \
  do {                            \
    const auto tmp_ = (v);        \
    std::memcpy((p), &tmp_, sizeof(tmp_)); \
  } while (0)

inline __attribute__((always_inline)) void Block(const float* src, size_t ss, float* dst,
                                                 size_t ds) {
  V8f r[8];
  for (int k = 0; k < 8; ++k) MJTOUCH_LOAD(r[k], src + k * ss);
  V8f t[8], u[8];
  for (int k = 0; k < 4; ++k) {
    t[2 * k] = __builtin_shufflevector(r[2 * k], r[2 * k + 1], 0, 8, 1, 9, 4, 12, 5, 13);
    t[2 * k + 1] = __builtin_shufflevector(r[2 * k], r[2 * k + 1], 2, 10, 3, 11, 6, 14, 7, 15);
  }
  for (int k = 0; k < 2; ++k) {
    const V8f a = t[4 * k], b = t[4 * k + 1], c = t[4 * k + 2], d = t[4 * k + 3];
    u[4 * k] = __builtin_shufflevector(a, c, 0, 1, 8, 9, 4, 5, 12, 13);
    u[4 * k + 1] = __builtin_shufflevector(a, c, 2, 3, 10, 11, 6, 7, 14, 15);
    u[4 * k + 2] = __builtin_shufflevector(b, d, 0, 1, 8, 9, 4, 5, 12, 13);
    u[4 * k + 3] = __builtin_shufflevector(b, d, 2, 3, 10, 11, 6, 7, 14, 15);
  }
  for (int k = 0; k < 4; ++k) {
    MJTOUCH_STORE(dst + k * ds, __builtin_shufflevector(u[k], u[k + 4], 0, 1, 2, 3, 8, 9, 10, 11));
    MJTOUCH_STORE(dst + (k + 4) * ds,
                  __builtin_shufflevector(u[k], u[k + 4], 4, 5, 6, 7, 12, 13, 14, 15));
  }
}

inline __attribute__((always_inline)) void Block(const double* src, size_t ss, double* dst,
                                                 size_t ds) {
  V4d r[4];
  for (int k = 0; k < 4; ++k) MJTOUCH_LOAD(r[k], src + k * ss);
  const V4d t0 = __builtin_shufflevector(r[0], r[1], 0, 4, 2, 6);
  const V4d t1 = __builtin_shufflevector(r[0], r[1], 1, 5, 3, 7);
  const V4d t2 = __builtin_shufflevector(r[2], r[3], 0, 4, 2, 6);
  const V4d t3 = __builtin_shufflevector(r[2], r[3], 1, 5, 3, 7);
  MJTOUCH_STORE(dst, __builtin_shufflevector(t0, t2, 0, 1, 4, 5));
  MJTOUCH_STORE(dst + ds, __builtin_shufflevector(t1, t3, 0, 1, 4, 5));
  MJTOUCH_STORE(dst + 2 * ds, __builtin_shufflevector(t0, t2, 2, 3, 6, 7));
  MJTOUCH_STORE(dst + 3 * ds, __builtin_shufflevector(t1, t3, 2, 3, 6, 7));
}
#undef MJTOUCH_LOAD
#undef MJTOUCH_STORE

template <typename T>
MJTOUCH_TARGET_CLONES
void TransposeT(const T* src, size_t ss, int rows, int cols, T* dst, size_t ds) {
  constexpr int W = 32 / sizeof(T);
  const int rb = rows / W * W, cb = cols / W * W;
  for (int r = 0; r < rb; r += W)
    for (int c = 0; c < cb; c += W) Block(src + r * ss + c, ss, dst + c * ds + r, ds);
  for (int r = 0; r < rows; ++r) {
    const int c0 = r < rb ? cb : 0;
    for (int c = c0; c < cols; ++c) dst[c * ds + r] = src[r * ss + c];
  }
}

template <typename T> struct VecOf;
template <> struct VecOf<float> { typedef V8f type; };
template <> struct VecOf<double> { typedef V4d type; };

// The split of ForwardColumns: Z = A + i B (A, B spectra of real columns),
// A = (Z(k) + conj Z(-k)) / 2, B = (Z(k) - conj Z(-k)) / (2 i), from the y
// pass's layout (wr / wi[ky * lw + c - c0]) straight into the spectrum rows
// (sre / sim[c * ss + ky], ky in [lo, hi); B in row c + h for c < cols - h).
// W x W tiles: rows ky and ny - ky as vectors along c, the four results
// transposed in registers (Block), instead of transposing Z first (a pass
// less). Each element's arithmetic is the scalar split's: the same bits.
template <typename T>
MJTOUCH_TARGET_CLONES
void SplitToSpectrum(const T* wr, const T* wi, size_t lw, int ny, int c0, int c1, int h,
                     int cols, int lo, int hi, T* sre, T* sim, size_t ss) {
  constexpr int W = 32 / sizeof(T);
  using V = typename VecOf<T>::type;
  const int nb = c1 - c0, b_lim = cols - h;
  const int kb = lo + (hi - lo) / W * W, jb = nb / W * W;
  alignas(32) T tile[4][W * W];
  alignas(32) T t[W * W];
  for (int k0 = lo; k0 < kb; k0 += W)
    for (int j0 = 0; j0 < jb; j0 += W) {
      for (int i = 0; i < W; ++i) {
        const int ky = k0 + i, km = ky == 0 ? 0 : ny - ky;
        V zr, zi, mr, mi;
        std::memcpy(&zr, wr + ky * lw + j0, sizeof(V));
        std::memcpy(&zi, wi + ky * lw + j0, sizeof(V));
        std::memcpy(&mr, wr + km * lw + j0, sizeof(V));
        std::memcpy(&mi, wi + km * lw + j0, sizeof(V));
        const V ar = T(0.5) * (zr + mr), ai = T(0.5) * (zi - mi);
        const V br = T(0.5) * (zi + mi), bi = T(-0.5) * (zr - mr);
        std::memcpy(tile[0] + i * W, &ar, sizeof(V));
        std::memcpy(tile[1] + i * W, &ai, sizeof(V));
        std::memcpy(tile[2] + i * W, &br, sizeof(V));
        std::memcpy(tile[3] + i * W, &bi, sizeof(V));
      }
      const int c = c0 + j0;
      Block(tile[0], W, sre + c * ss + k0, ss);
      Block(tile[1], W, sim + c * ss + k0, ss);
      if (c + W <= b_lim) {
        Block(tile[2], W, sre + (c + h) * ss + k0, ss);
        Block(tile[3], W, sim + (c + h) * ss + k0, ss);
      } else {
        for (int q = 0; q < 2; ++q) {
          T* dst = q == 0 ? sre : sim;
          Block(tile[2 + q], W, t, W);
          for (int j = 0; j < W && c + j < b_lim; ++j)
            std::memcpy(dst + (c + j + h) * ss + k0, t + j * W, sizeof(V));
        }
      }
    }
  // The edges (ky >= kb, or lanes >= jb) one by one.
  for (int j = 0; j < nb; ++j) {
    const int c = c0 + j;
    for (int ky = j < jb ? kb : lo; ky < hi; ++ky) {
      const int km = ky == 0 ? 0 : ny - ky;
      const T zr = wr[ky * lw + j], zi = wi[ky * lw + j];
      const T mr = wr[km * lw + j], mi = wi[km * lw + j];
      sre[c * ss + ky] = T(0.5) * (zr + mr);
      sim[c * ss + ky] = T(0.5) * (zi - mi);
      if (c < b_lim) {
        sre[(c + h) * ss + ky] = T(0.5) * (zi + mi);
        sim[(c + h) * ss + ky] = T(-0.5) * (zr - mr);
      }
    }
  }
}

// The merge of InverseColumns: Z = A + i B over the full ky range from the
// half spectra (sre / sim[c * ss + ky], ky in [lo, hi); B in row c + h), the
// upper half from A(-k) = conj A(k), straight into the y pass's layout
// (wr / wi[ky * lw + c - c0]): W x W tiles of A and B transposed in
// registers (Block), then rows ky and ny - ky as vectors along c. Columns
// without a B (c >= cols - h) and the edges go one by one. x - (-y) ==
// x + y and (-x) + y == y - x exactly: the conjugate half rounds as
// sgn * (...) would; each element's arithmetic is the scalar merge's.
template <typename T>
MJTOUCH_TARGET_CLONES
void MergeFromSpectrum(const T* sre, const T* sim, size_t ss, int ny, int top, int c0, int c1,
                       int h, int cols, int lo, int hi, T* wr, T* wi, size_t lw) {
  constexpr int W = 32 / sizeof(T);
  using V = typename VecOf<T>::type;
  const int nb = c1 - c0, b_lim = cols - h;
  const int kb = lo + (hi - lo) / W * W;
  const int jb = std::max(0, std::min(nb, b_lim - c0)) / W * W;
  const int m0 = std::max(lo, 1), m1 = std::min(hi, top + 1);  // mirrored: ky = ny - m
  alignas(32) T ar[W * W], ai[W * W], br[W * W], bi[W * W];
  for (int k0 = lo; k0 < kb; k0 += W)
    for (int j0 = 0; j0 < jb; j0 += W) {
      const int c = c0 + j0;
      Block(sre + c * ss + k0, ss, ar, W);
      Block(sim + c * ss + k0, ss, ai, W);
      Block(sre + (c + h) * ss + k0, ss, br, W);
      Block(sim + (c + h) * ss + k0, ss, bi, W);
      for (int i = 0; i < W; ++i) {
        const int ky = k0 + i;
        V a_r, a_i, b_r, b_i;
        std::memcpy(&a_r, ar + i * W, sizeof(V));
        std::memcpy(&a_i, ai + i * W, sizeof(V));
        std::memcpy(&b_r, br + i * W, sizeof(V));
        std::memcpy(&b_i, bi + i * W, sizeof(V));
        const V zr = a_r - b_i, zi = a_i + b_r;
        std::memcpy(wr + ky * lw + j0, &zr, sizeof(V));
        std::memcpy(wi + ky * lw + j0, &zi, sizeof(V));
        if (ky >= m0 && ky < m1) {
          const V mr = a_r + b_i, mi = b_r - a_i;
          std::memcpy(wr + (ny - ky) * lw + j0, &mr, sizeof(V));
          std::memcpy(wi + (ny - ky) * lw + j0, &mi, sizeof(V));
        }
      }
    }
  for (int j = 0; j < nb; ++j) {
    const int c = c0 + j;
    const T* a_r = sre + c * ss;
    const T* a_i = sim + c * ss;
    for (int ky = j < jb ? kb : lo; ky < hi; ++ky) {
      const bool mirror = ky >= m0 && ky < m1;
      if (c < b_lim) {
        const T b_r = sre[(c + h) * ss + ky], b_i = sim[(c + h) * ss + ky];
        wr[ky * lw + j] = a_r[ky] - b_i;
        wi[ky * lw + j] = a_i[ky] + b_r;
        if (mirror) {
          wr[(ny - ky) * lw + j] = a_r[ky] + b_i;
          wi[(ny - ky) * lw + j] = b_r - a_i[ky];
        }
      } else {
        wr[ky * lw + j] = a_r[ky] - T(0);
        wi[ky * lw + j] = a_i[ky] + T(0);
        if (mirror) {
          wr[(ny - ky) * lw + j] = a_r[ky] - T(0);
          wi[(ny - ky) * lw + j] = -a_i[ky] + T(0);
        }
      }
    }
  }
}

// Scratch for a 2D transform: the y-pass work arrays (W each) and the
// stages' ping-pong arrays (max(W, spectrum) each), in one buffer.
template <typename T>
void SplitScratch(size_t W, size_t spectrum, std::vector<T>* scratch, T** wr, T** wi, T** sr,
                  T** si) {
  // 64-byte aligned arrays (see PaddedStride), each a whole number of lines.
  constexpr size_t kLine = 64 / sizeof(T);
  W = (W + kLine - 1) / kLine * kLine;
  const size_t S = (std::max(W, spectrum) + kLine - 1) / kLine * kLine;
  scratch->resize(2 * W + 2 * S + kLine);
  const size_t misalign = reinterpret_cast<uintptr_t>(scratch->data()) % 64 / sizeof(T);
  *wr = scratch->data() + (misalign ? kLine - misalign : 0);
  *wi = *wr + W;
  *sr = *wi + W;
  *si = *sr + S;
}
}  // namespace

Fft2D::Fft2D(int nx, int ny)
    : nx_(nx), ny_(ny), spec_stride_(PaddedStride(ny)), px_(nx), py_(ny) {}

void Fft2D::Forward(const double* re, const double* im, int stride, int rows, int cols, double* spec_re,
                    double* spec_im, std::vector<double>* scratch) const {
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

void Fft2D::Inverse(double* spec_re, double* spec_im, int rows, int cols, double* re, double* im, int stride,
                    std::vector<double>* scratch) const {
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

// The real transforms in parts that own disjoint memory, so that
// ConvolveReal can run them on threads without sharing cache lines: the y
// pass by packed columns [c0, c1) (its own work slab wr / wi, row stride
// lw), the x pass by ky lanes (one Slab of the spectrum each). Transform's
// arithmetic per lane depends on neither the batch nor the strides, and
// each part's stage scratch is its own slice of sr / si (ny elements per
// packed column, nx per ky lane), so any split gives the bits of a single
// part (ForwardReal, InverseReal).
template <typename T>
void Fft2D::ForwardColumns(const double* re, int stride, int rows, int cols, int c0, int c1,
                           T* wr, T* wi, int lw, const Slab* slabs, int nslabs, T* spec_re,
                           T* spec_im, T* sr, T* si) const {
  if (c0 >= c1) return;
  const int h = (cols + 1) / 2;  // column c is packed with column c + h
  const int nb = c1 - c0;
  // Rows >= rows are zero; in the others, the part's lanes are all written
  // (wi's last one is zero when cols is odd). With rows <= ny / 2 the
  // transform reads rows < ny / 2 only (Transform's nonzero): the others
  // need no clearing.
  const int zero_end = py_.SkipsUpperHalf(rows) ? ny_ / 2 : ny_;
  for (int y = rows; y < zero_end; ++y) {
    std::fill(wr + static_cast<size_t>(y) * lw, wr + static_cast<size_t>(y) * lw + nb, T(0));
    std::fill(wi + static_cast<size_t>(y) * lw, wi + static_cast<size_t>(y) * lw + nb, T(0));
  }
  const int b_end = std::max(c0, std::min(c1, cols - h));
  for (int y = 0; y < rows; ++y) {
    const double* row = re + static_cast<size_t>(y) * stride;
    T* a = wr + static_cast<size_t>(y) * lw - c0;  // indexed by column
    T* b = wi + static_cast<size_t>(y) * lw - c0;
    for (int x = c0; x < c1; ++x) a[x] = static_cast<T>(row[x]);
    for (int x = c0; x < b_end; ++x) b[x] = static_cast<T>(row[h + x]);
    for (int x = b_end; x < c1; ++x) b[x] = T(0);
  }
  const size_t ts = static_cast<size_t>(ny_);
  py_.Transform(wr, wi, nb, lw, false, sr + c0 * ts, si + c0 * ts, rows);
  for (int q = 0; q < nslabs; ++q) {
    const Slab& sl = slabs[q];
    SplitToSpectrum(wr, wi, lw, ny_, c0, c1, h, cols, sl.lo, sl.hi,
                    spec_re + sl.offset - sl.lo, spec_im + sl.offset - sl.lo, sl.stride);
  }
}

template <typename T>
void Fft2D::ForwardLanes(int cols, const Slab& sl, T* spec_re, T* spec_im, T* sr, T* si) const {
  const int nb = sl.hi - sl.lo;
  if (nb <= 0) return;
  T* re = spec_re + sl.offset;
  T* im = spec_im + sl.offset;
  // columns >= cols are zero (those the transform reads: as above)
  const int zero_x = px_.SkipsUpperHalf(cols) ? nx_ / 2 : nx_;
  for (int x = cols; x < zero_x; ++x) {
    std::fill(re + static_cast<size_t>(x) * sl.stride, re + static_cast<size_t>(x) * sl.stride + nb, T(0));
    std::fill(im + static_cast<size_t>(x) * sl.stride, im + static_cast<size_t>(x) * sl.stride + nb, T(0));
  }
  const size_t tn = static_cast<size_t>(nx_);
  px_.Transform(re, im, nb, sl.stride, false, sr + sl.lo * tn, si + sl.lo * tn, cols);
}

template <typename T>
void Fft2D::InverseLanes(int cols, const Slab& sl, T* spec_re, T* spec_im, T* sr, T* si,
                         const T* k_hat) const {
  const int nb = sl.hi - sl.lo;
  if (nb <= 0) return;
  // columns x < cols only are read below
  const size_t tn = static_cast<size_t>(nx_);
  px_.Transform(spec_re + sl.offset, spec_im + sl.offset, nb, sl.stride, true, sr + sl.lo * tn,
                si + sl.lo * tn, -1, cols, k_hat ? k_hat + sl.lo : nullptr, spec_stride_);
}

template <typename T>
void Fft2D::InverseColumns(T* spec_re, T* spec_im, const Slab* slabs, int nslabs, int rows,
                           int cols, int c0, int c1, double* re, int stride, T* wr, T* wi,
                           int lw, T* sr, T* si) const {
  if (c0 >= c1) return;
  const int h = (cols + 1) / 2;
  const int nb = c1 - c0;
  const int hy = half_ny(), top = ny_ - hy;  // ky >= hy pair with 1 <= ny - ky <= top
  // Z = A + i B over the full ky range, the upper half from A(-k) =
  // conj A(k) (the columns' inverses are real), into the y pass's layout.
  for (int q = 0; q < nslabs; ++q) {
    const Slab& sl = slabs[q];
    MergeFromSpectrum<T>(spec_re + sl.offset - sl.lo, spec_im + sl.offset - sl.lo, sl.stride, ny_,
                         top, c0, c1, h, cols, sl.lo, sl.hi, wr, wi, lw);
  }
  const size_t ts = static_cast<size_t>(ny_);
  py_.Transform(wr, wi, nb, lw, true, sr + c0 * ts, si + c0 * ts, -1, rows);
  const int b_end = std::max(c0, std::min(c1, cols - h));
  for (int y = 0; y < rows; ++y) {
    double* row = re + static_cast<size_t>(y) * stride;
    const T* a = wr + static_cast<size_t>(y) * lw - c0;
    const T* b = wi + static_cast<size_t>(y) * lw - c0;
    for (int x = c0; x < c1; ++x) row[x] = static_cast<double>(a[x]);
    for (int x = c0; x < b_end; ++x) row[h + x] = static_cast<double>(b[x]);
  }
}

template <typename T>
void Fft2D::ForwardReal(const double* re, int stride, int rows, int cols, T* spec_re, T* spec_im,
                        std::vector<T>* scratch) const {
  const int h = (cols + 1) / 2, lw = PaddedStride(h);
  const size_t W = static_cast<size_t>(ny_) * lw;
  T *wr, *wi, *sr, *si;
  SplitScratch(W, spectrum_size(), scratch, &wr, &wi, &sr, &si);
  const Slab all{0, half_ny(), 0, spec_stride_};
  ForwardColumns(re, stride, rows, cols, 0, h, wr, wi, lw, &all, 1, spec_re, spec_im, sr, si);
  ForwardLanes(cols, all, spec_re, spec_im, sr, si);
}

template <typename T>
void Fft2D::InverseReal(T* spec_re, T* spec_im, int rows, int cols, double* re, int stride,
                        std::vector<T>* scratch) const {
  const int h = (cols + 1) / 2, lw = PaddedStride(h);
  const size_t W = static_cast<size_t>(ny_) * lw;
  T *wr, *wi, *sr, *si;
  SplitScratch(W, spectrum_size(), scratch, &wr, &wi, &sr, &si);
  const Slab all{0, half_ny(), 0, spec_stride_};
  InverseLanes(cols, all, spec_re, spec_im, sr, si);
  InverseColumns(spec_re, spec_im, &all, 1, rows, cols, 0, h, re, stride, wr, wi, lw, sr, si);
}

namespace {
// Bounds of part k of `parts` over [0, n): the even split rounded to the
// nearest multiple of `align` (whole vectors per part), the last part
// ending at n.
inline int PartBound(int n, int parts, int k, int align) {
  if (k >= parts) return n;
  const long long even = static_cast<long long>(n) * k / parts;
  return std::min(n, static_cast<int>((even + align / 2) / align * align));
}

constexpr int kMaxParts = 16;
}  // namespace

template <typename T>
void Fft2D::ConvolveReal(const double* in, int in_stride, int in_rows, int in_cols, const T* k_hat,
                         int out_rows, int out_cols, double* out, int out_stride, T* spec_re,
                         T* spec_im, std::vector<T>* scratch, int threads) const {
  const int h_in = (in_cols + 1) / 2, h_out = (out_cols + 1) / 2, hy = half_ny();
  const int ls = spec_stride_;
  constexpr int kAlign = 32 / sizeof(T);  // whole AVX vectors (FftPlan::Transform's scratch rows)
  auto parts = [&](int n) {
    return std::max(1, std::min(std::min(threads, kMaxParts), (n + kAlign - 1) / kAlign));
  };
  const int pa = parts(h_in), pb = parts(hy), pc = parts(h_out);
  // The spectrum's ky lanes in pb slabs, one after another (each part's
  // rows contiguous: no cache line shared by two threads' x passes).
  Slab slabs[kMaxParts];
  size_t spec_used = 0;
  for (int k = 0; k < pb; ++k) {
    const int lo = PartBound(hy, pb, k, kAlign), hi = PartBound(hy, pb, k + 1, kAlign);
    const int stride = pb == 1 ? ls : PaddedStride(hi - lo);
    slabs[k] = Slab{lo, hi, spec_used, stride};
    spec_used += static_cast<size_t>(nx_) * stride;
  }
  // The y passes' work slabs likewise, per packed column part.
  auto slab_sizes = [&](int h, int np, int* lw, size_t* off) {
    size_t used = 0;
    for (int k = 0; k < np; ++k) {
      lw[k] = PaddedStride(np == 1 ? h : PartBound(h, np, k + 1, kAlign) - PartBound(h, np, k, kAlign));
      off[k] = used;
      used += static_cast<size_t>(ny_) * lw[k];
    }
    return used;
  };
  int lw_a[kMaxParts], lw_c[kMaxParts];
  size_t off_a[kMaxParts], off_c[kMaxParts];
  const size_t W = std::max(slab_sizes(h_in, pa, lw_a, off_a), slab_sizes(h_out, pc, lw_c, off_c));
  T *wr, *wi, *sr, *si;
  SplitScratch(W, spectrum_size(), scratch, &wr, &wi, &sr, &si);
  const bool parallel = threads > 1 && spec_used <= spectrum_size() && (pa > 1 || pb > 1 || pc > 1);
  if (!parallel) {
    const Slab all{0, hy, 0, ls};
    ForwardColumns(in, in_stride, in_rows, in_cols, 0, h_in, wr, wi, PaddedStride(h_in), &all, 1,
                   spec_re, spec_im, sr, si);
    ForwardLanes(in_cols, all, spec_re, spec_im, sr, si);
    InverseLanes(out_cols, all, spec_re, spec_im, sr, si, k_hat);
    InverseColumns(spec_re, spec_im, &all, 1, out_rows, out_cols, 0, h_out, out, out_stride, wr,
                   wi, PaddedStride(h_out), sr, si);
    return;
  }
  // Three passes, each split into parts that write disjoint memory; the
  // bits do not depend on the split (see ForwardColumns), so the parts
  // follow the thread count.
  ThreadPool& pool = ThreadPool::Shared();
  pool.Run(pa, threads, [&](int k) {
    ForwardColumns(in, in_stride, in_rows, in_cols, PartBound(h_in, pa, k, kAlign),
                   PartBound(h_in, pa, k + 1, kAlign), wr + off_a[k], wi + off_a[k], lw_a[k],
                   slabs, pb, spec_re, spec_im, sr, si);
  });
  pool.Run(pb, threads, [&](int k) {
    const Slab& sl = slabs[k];
    ForwardLanes(in_cols, sl, spec_re, spec_im, sr, si);
    InverseLanes(out_cols, sl, spec_re, spec_im, sr, si, k_hat);
  });
  pool.Run(pc, threads, [&](int k) {
    InverseColumns(spec_re, spec_im, slabs, pb, out_rows, out_cols,
                   PartBound(h_out, pc, k, kAlign), PartBound(h_out, pc, k + 1, kAlign), out,
                   out_stride, wr + off_c[k], wi + off_c[k], lw_c[k], sr, si);
  });
}

#define MJTOUCH_FFT_REAL(T)                                                                  \
  template void Fft2D::ForwardReal(const double*, int, int, int, T*, T*, std::vector<T>*)    \
      const;                                                                                 \
  template void Fft2D::InverseReal(T*, T*, int, int, double*, int, std::vector<T>*) const;    \
  template void Fft2D::ConvolveReal(const double*, int, int, int, const T*, int, int, double*, \
                                    int, T*, T*, std::vector<T>*, int) const;
MJTOUCH_FFT_REAL(double)
MJTOUCH_FFT_REAL(float)
#undef MJTOUCH_FFT_REAL


}  // namespace mjtouch
