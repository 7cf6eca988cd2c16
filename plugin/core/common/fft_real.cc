// Fft2D's real transforms (ForwardReal, InverseReal, ConvolveReal): the
// column pairs packed into one complex y pass, the half spectrum's x pass.
#include <algorithm>
#include <cstring>

#include "common/fft.h"
#include "common/fft_layout.h"
#include "common/simd.h"
#include "common/thread_pool.h"

namespace mjtouch {
namespace {

using fft_detail::Block;
using fft_detail::PaddedStride;
using fft_detail::SplitScratch;
using fft_detail::VecOf;

// The split of ForwardColumns: Z = A + i B (A, B spectra of real columns),
// A = (Z(k) + conj Z(-k)) / 2, B = (Z(k) - conj Z(-k)) / (2 i), from the y
// pass's layout (wr / wi[ky * lw + c - c0]) straight into the spectrum rows
// (sre / sim[c * ss + ky], ky in [lo, hi); B in row c + h for c < cols - h).
// W x W tiles: rows ky and ny - ky as vectors along c, the four results
// transposed in registers (Block), instead of transposing Z first (a pass
// less). Each element's arithmetic is the scalar split's: the same bits.
template <typename T>
MJTOUCH_TARGET_CLONES void SplitToSpectrum(const T* wr, const T* wi, size_t lw, int ny, int c0,
                                           int c1, int h, int cols, int lo, int hi, T* sre, T* sim,
                                           size_t ss) {
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
MJTOUCH_TARGET_CLONES void MergeFromSpectrum(const T* sre, const T* sim, size_t ss, int ny, int top,
                                             int c0, int c1, int h, int cols, int lo, int hi, T* wr,
                                             T* wi, size_t lw) {
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

}  // namespace

// The real transforms in parts that own disjoint memory, so that
// ConvolveReal can run them on threads without sharing cache lines: the y
// pass by packed columns [c0, c1) (its own work slab wr / wi, row stride
// lw), the x pass by ky lanes (one Slab of the spectrum each). Transform's
// arithmetic per lane depends on neither the batch nor the strides, and
// each part's stage scratch is its own slice of sr / si (ny elements per
// packed column, nx per ky lane), so any split gives the bits of a single
// part (ForwardReal, InverseReal).
template <typename T>
void Fft2D::ForwardColumns(const double* re, int stride, int rows, int cols, int c0, int c1, T* wr,
                           T* wi, int lw, const Slab* slabs, int nslabs, T* spec_re, T* spec_im,
                           T* sr, T* si) const {
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
    SplitToSpectrum(wr, wi, lw, ny_, c0, c1, h, cols, sl.lo, sl.hi, spec_re + sl.offset - sl.lo,
                    spec_im + sl.offset - sl.lo, sl.stride);
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
    std::fill(re + static_cast<size_t>(x) * sl.stride, re + static_cast<size_t>(x) * sl.stride + nb,
              T(0));
    std::fill(im + static_cast<size_t>(x) * sl.stride, im + static_cast<size_t>(x) * sl.stride + nb,
              T(0));
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
                           int cols, int c0, int c1, double* re, int stride, T* wr, T* wi, int lw,
                           T* sr, T* si) const {
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
      lw[k] =
          PaddedStride(np == 1 ? h : PartBound(h, np, k + 1, kAlign) - PartBound(h, np, k, kAlign));
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
    InverseColumns(spec_re, spec_im, &all, 1, out_rows, out_cols, 0, h_out, out, out_stride, wr, wi,
                   PaddedStride(h_out), sr, si);
    return;
  }
  // Three passes, each split into parts that write disjoint memory; the
  // bits do not depend on the split (see ForwardColumns), so the parts
  // follow the thread count.
  ThreadPool& pool = ThreadPool::Shared();
  pool.Run(pa, threads, [&](int k) {
    ForwardColumns(in, in_stride, in_rows, in_cols, PartBound(h_in, pa, k, kAlign),
                   PartBound(h_in, pa, k + 1, kAlign), wr + off_a[k], wi + off_a[k], lw_a[k], slabs,
                   pb, spec_re, spec_im, sr, si);
  });
  pool.Run(pb, threads, [&](int k) {
    const Slab& sl = slabs[k];
    ForwardLanes(in_cols, sl, spec_re, spec_im, sr, si);
    InverseLanes(out_cols, sl, spec_re, spec_im, sr, si, k_hat);
  });
  pool.Run(pc, threads, [&](int k) {
    InverseColumns(spec_re, spec_im, slabs, pb, out_rows, out_cols, PartBound(h_out, pc, k, kAlign),
                   PartBound(h_out, pc, k + 1, kAlign), out, out_stride, wr + off_c[k],
                   wi + off_c[k], lw_c[k], sr, si);
  });
}

#define MJTOUCH_FFT_REAL(T)                                                                      \
  template void Fft2D::ForwardReal(const double*, int, int, int, T*, T*, std::vector<T>*) const; \
  template void Fft2D::InverseReal(T*, T*, int, int, double*, int, std::vector<T>*) const;       \
  template void Fft2D::ConvolveReal(const double*, int, int, int, const T*, int, int, double*,   \
                                    int, T*, T*, std::vector<T>*, int) const;
MJTOUCH_FFT_REAL(double)
MJTOUCH_FFT_REAL(float)
#undef MJTOUCH_FFT_REAL

}  // namespace mjtouch
