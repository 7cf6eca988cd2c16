// Internal to the FFTs (fft.cc): the butterflies of one Stockham stage over
// a batch of lanes, plain and fused two stages at a time. Not a public API.
#ifndef MJTOUCH_COMMON_FFT_KERNELS_H_
#define MJTOUCH_COMMON_FFT_KERNELS_H_

#include <cstddef>

namespace mjtouch {
namespace fft_detail {

// The radix-R DFT of one lane: y[r] for r < kOut (radix 5: 3 or 5; radix
// 3: 2 or 3). sg: forward +1, inverse -1.
template <int R, bool kInverse, typename T, int kOut = R>
inline __attribute__((always_inline)) void Dft(const T* xr, const T* xi, T* yr, T* yi) {
  constexpr T sg = kInverse ? T(-1) : T(1);
  const T c3 = T(-0.5), s3 = T(0.86602540378443864676);
  const T c51 = T(0.30901699437494742410), c52 = T(-0.80901699437494742410);
  const T s51 = T(0.95105651629515357212), s52 = T(0.58778525229247312917);
  if constexpr (R == 2) {
    yr[0] = xr[0] + xr[1];
    yi[0] = xi[0] + xi[1];
    yr[1] = xr[0] - xr[1];
    yi[1] = xi[0] - xi[1];
  } else if constexpr (R == 3) {
    const T tr = xr[1] + xr[2], ti = xi[1] + xi[2];
    const T mr = xr[0] + c3 * tr, mi = xi[0] + c3 * ti;
    const T dr = s3 * (xr[1] - xr[2]), di = s3 * (xi[1] - xi[2]);
    yr[0] = xr[0] + tr;
    yi[0] = xi[0] + ti;
    yr[1] = mr + sg * di;
    yi[1] = mi - sg * dr;
    if constexpr (kOut == 3) {
      yr[2] = mr - sg * di;
      yi[2] = mi + sg * dr;
    }
  } else if constexpr (R == 4) {
    const T t0r = xr[0] + xr[2], t0i = xi[0] + xi[2];
    const T t1r = xr[0] - xr[2], t1i = xi[0] - xi[2];
    const T t2r = xr[1] + xr[3], t2i = xi[1] + xi[3];
    const T t3r = xr[1] - xr[3], t3i = xi[1] - xi[3];
    yr[0] = t0r + t2r;
    yi[0] = t0i + t2i;
    yr[2] = t0r - t2r;
    yi[2] = t0i - t2i;
    yr[1] = t1r + sg * t3i;
    yi[1] = t1i - sg * t3r;
    yr[3] = t1r - sg * t3i;
    yi[3] = t1i + sg * t3r;
  } else if constexpr (R == 8) {
    // Even and odd halves as radix-4 DFTs, the odd one times w8^k
    // (w8 = exp(-+ 2 pi i / 8): multiples of (1 -+ i) / sqrt 2, -+i).
    const T r2 = T(0.70710678118654752440);
    T er[4], ei[4], pr[4], pi[4];
    for (int q = 0; q < 2; ++q) {
      const T ar[4] = {xr[q], xr[q + 2], xr[q + 4], xr[q + 6]};
      const T ai[4] = {xi[q], xi[q + 2], xi[q + 4], xi[q + 6]};
      Dft<4, kInverse>(ar, ai, q == 0 ? er : pr, q == 0 ? ei : pi);
    }
    const T o1r = (pr[1] + sg * pi[1]) * r2, o1i = (pi[1] - sg * pr[1]) * r2;
    const T o2r = sg * pi[2], o2i = -sg * pr[2];
    const T o3r = (sg * pi[3] - pr[3]) * r2, o3i = (-sg * pr[3] - pi[3]) * r2;
    const T qr[4] = {pr[0], o1r, o2r, o3r}, qi[4] = {pi[0], o1i, o2i, o3i};
    for (int k = 0; k < 4; ++k) {
      yr[k] = er[k] + qr[k];
      yi[k] = ei[k] + qi[k];
      yr[k + 4] = er[k] - qr[k];
      yi[k + 4] = ei[k] - qi[k];
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
    yr[0] = xr[0] + t1r + t2r;
    yi[0] = xi[0] + t1i + t2i;
    yr[1] = m1r + sg * e1i;
    yi[1] = m1i - sg * e1r;
    yr[2] = m2r + sg * e2i;
    yi[2] = m2i - sg * e2r;
    if constexpr (kOut == 5) {
      yr[4] = m1r - sg * e1i;
      yi[4] = m1i + sg * e1r;
      yr[3] = m2r - sg * e2i;
      yi[3] = m2i + sg * e2r;
    }
  }
}

// x times w (complex), the rounding every twiddle of every stage uses.
template <typename T>
inline __attribute__((always_inline)) void Twiddle(T a, T c, T w_r, T w_i, T* xr, T* xi) {
  *xr = a * w_r - c * w_i;
  *xi = a * w_i + c * w_r;
}

// The butterflies of one j over lanes [0, batch). kTwiddle: multiply the
// inputs r >= 1 by w[r] first. Pointers are restrict-qualified and the
// lanes independent, so the loop vectorises (no gathers, no branches).
// kOut: Dft's (a last stage's outputs r < kOut only).
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
        Twiddle(a, c, w_r[r], w_i[r], &xr[r], &xi[r]);
      } else {
        xr[r] = a;
        xi[r] = c;
      }
    }
    T yr[R], yi[R];
    Dft<R, kInverse, T, kOut>(xr, xi, yr, yi);
    for (int r = 0; r < kOut; ++r) {
      out_re[r * out_step + b] = yr[r];
      out_im[r * out_step + b] = yi[r];
    }
  }
}

// Two consecutive stages, radix Ra (span s) then Rb (span s Ra), as one
// radix Ra Rb stage of span s held in registers: a pass over the data less,
// the same operations on the same values as the two stages (the same bits).
// Group j (j mod s = jm) reads elements j + t n/R, t = q + r Rb: A butterfly
// q < Rb takes inputs r < Ra, twiddled by wa[r] (stage A's row jm), and its
// output r is B butterfly r's input q, twiddled by wb[r][q] (stage B's row
// r s + jm); B's output u goes to t = r + u Ra of the stage's output
// (element (j / s) s R + jm + t s). kFirst (jm == 0): the stages'
// untwiddled butterflies (A's all, B's r = 0) skip the multiplication as
// they do. kHalfA: Ra == 2 with zero inputs r = 1 (Transform's nonzero), A's
// outputs both x (FirstStage2HalfInput's copies).
template <int Ra, int Rb, bool kInverse, bool kFirst, bool kHalfA, bool kInPlace, typename T>
inline __attribute__((always_inline)) void FusedButterflies(
    const T* __restrict in_re_arg, const T* __restrict in_im_arg, size_t in_step_arg,
    T* __restrict out_re, T* __restrict out_im, size_t out_step, const T (&wa_r)[Ra],
    const T (&wa_i)[Ra], const T (&wb_r)[Ra][Rb], const T (&wb_i)[Ra][Rb], int batch) {
  static_assert(!kHalfA || (Ra == 2 && kFirst), "half input: a first radix-2 stage");
  const T* in_re = kInPlace ? out_re : in_re_arg;
  const T* in_im = kInPlace ? out_im : in_im_arg;
  const size_t in_step = kInPlace ? out_step : in_step_arg;
#pragma GCC ivdep
  for (int b = 0; b < batch; ++b) {
    T mr[Ra][Rb], mi[Ra][Rb];  // A's output r of butterfly q
    for (int q = 0; q < Rb; ++q) {
      if constexpr (kHalfA) {
        mr[0][q] = mr[1][q] = in_re[q * in_step + b];
        mi[0][q] = mi[1][q] = in_im[q * in_step + b];
      } else {
        T xr[Ra], xi[Ra], yr[Ra], yi[Ra];
        for (int r = 0; r < Ra; ++r) {
          const T a = in_re[(q + r * Rb) * in_step + b], c = in_im[(q + r * Rb) * in_step + b];
          if (kFirst || r == 0) {
            xr[r] = a;
            xi[r] = c;
          } else {
            Twiddle(a, c, wa_r[r], wa_i[r], &xr[r], &xi[r]);
          }
        }
        Dft<Ra, kInverse, T>(xr, xi, yr, yi);
        for (int r = 0; r < Ra; ++r) {
          mr[r][q] = yr[r];
          mi[r][q] = yi[r];
        }
      }
    }
    for (int r = 0; r < Ra; ++r) {
      T xr[Rb], xi[Rb], yr[Rb], yi[Rb];
      for (int q = 0; q < Rb; ++q) {
        if ((kFirst && r == 0) || q == 0) {
          xr[q] = mr[r][q];
          xi[q] = mi[r][q];
        } else {
          Twiddle(mr[r][q], mi[r][q], wb_r[r][q], wb_i[r][q], &xr[q], &xi[q]);
        }
      }
      Dft<Rb, kInverse, T>(xr, xi, yr, yi);
      for (int u = 0; u < Rb; ++u) {
        out_re[(r + u * Ra) * out_step + b] = yr[u];
        out_im[(r + u * Ra) * out_step + b] = yi[u];
      }
    }
  }
}

}  // namespace fft_detail
}  // namespace mjtouch

#endif  // MJTOUCH_COMMON_FFT_KERNELS_H_
