#include "common/fft.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace mjtouch {
namespace {

constexpr double kPi = 3.14159265358979323846;

// One Stockham stage (Govindaraju et al. 2008, mixed radix): reads element
// j + r n/R, twiddles by exp(-+2 pi i r (j mod Ns) / (Ns R)), does a radix-R
// DFT and writes element (j / Ns) Ns R + (j mod Ns) + r Ns. Output is in
// natural order after the last stage. Every loop over b is independent per
// lane (no reductions), so vectorised and scalar code round alike.
template <int R, bool kInverse>
__attribute__((target_clones("avx2", "default")))
void Stage(int n, int span, const double* tw_re, const double* tw_im, const double* in_re,
           const double* in_im, int in_stride, double* out_re, double* out_im,
           int out_stride, int batch) {
  const int m = n / R;
  // Rotation by -i (forward) or +i (inverse): (x, y) -> (s y, -s x).
  constexpr double sg = kInverse ? -1.0 : 1.0;
  const double c3 = -0.5, s3 = 0.86602540378443864676;
  const double c51 = 0.30901699437494742410, c52 = -0.80901699437494742410;
  const double s51 = 0.95105651629515357212, s52 = 0.58778525229247312917;
  for (int j = 0; j < m; ++j) {
    const int jm = j % span;
    const int dst = (j / span) * span * R + jm;
    double wr[R], wi[R];
    for (int r = 0; r < R; ++r) {
      wr[r] = tw_re[jm * R + r];
      wi[r] = kInverse ? -tw_im[jm * R + r] : tw_im[jm * R + r];
    }
    const double* ir[R];
    const double* ii[R];
    double* orr[R];
    double* oi[R];
    for (int r = 0; r < R; ++r) {
      ir[r] = in_re + static_cast<size_t>(j + r * m) * in_stride;
      ii[r] = in_im + static_cast<size_t>(j + r * m) * in_stride;
      orr[r] = out_re + static_cast<size_t>(dst + r * span) * out_stride;
      oi[r] = out_im + static_cast<size_t>(dst + r * span) * out_stride;
    }
    const bool twiddle = jm != 0;
    for (int b = 0; b < batch; ++b) {
      double xr[R], xi[R];
      xr[0] = ir[0][b];
      xi[0] = ii[0][b];
      for (int r = 1; r < R; ++r) {
        const double a = ir[r][b], c = ii[r][b];
        if (twiddle) {
          xr[r] = a * wr[r] - c * wi[r];
          xi[r] = a * wi[r] + c * wr[r];
        } else {
          xr[r] = a;
          xi[r] = c;
        }
      }
      if constexpr (R == 2) {
        orr[0][b] = xr[0] + xr[1];
        oi[0][b] = xi[0] + xi[1];
        orr[1][b] = xr[0] - xr[1];
        oi[1][b] = xi[0] - xi[1];
      } else if constexpr (R == 3) {
        const double tr = xr[1] + xr[2], ti = xi[1] + xi[2];
        const double mr = xr[0] + c3 * tr, mi = xi[0] + c3 * ti;
        const double dr = s3 * (xr[1] - xr[2]), di = s3 * (xi[1] - xi[2]);
        orr[0][b] = xr[0] + tr;
        oi[0][b] = xi[0] + ti;
        orr[1][b] = mr + sg * di;
        oi[1][b] = mi - sg * dr;
        orr[2][b] = mr - sg * di;
        oi[2][b] = mi + sg * dr;
      } else if constexpr (R == 4) {
        const double t0r = xr[0] + xr[2], t0i = xi[0] + xi[2];
        const double t1r = xr[0] - xr[2], t1i = xi[0] - xi[2];
        const double t2r = xr[1] + xr[3], t2i = xi[1] + xi[3];
        const double t3r = xr[1] - xr[3], t3i = xi[1] - xi[3];
        orr[0][b] = t0r + t2r;
        oi[0][b] = t0i + t2i;
        orr[2][b] = t0r - t2r;
        oi[2][b] = t0i - t2i;
        orr[1][b] = t1r + sg * t3i;
        oi[1][b] = t1i - sg * t3r;
        orr[3][b] = t1r - sg * t3i;
        oi[3][b] = t1i + sg * t3r;
      } else {
        static_assert(R == 5, "radix");
        const double t1r = xr[1] + xr[4], t1i = xi[1] + xi[4];
        const double t2r = xr[2] + xr[3], t2i = xi[2] + xi[3];
        const double d1r = xr[1] - xr[4], d1i = xi[1] - xi[4];
        const double d2r = xr[2] - xr[3], d2i = xi[2] - xi[3];
        const double m1r = xr[0] + c51 * t1r + c52 * t2r, m1i = xi[0] + c51 * t1i + c52 * t2i;
        const double m2r = xr[0] + c52 * t1r + c51 * t2r, m2i = xi[0] + c52 * t1i + c51 * t2i;
        const double e1r = s51 * d1r + s52 * d2r, e1i = s51 * d1i + s52 * d2i;
        const double e2r = s52 * d1r - s51 * d2r, e2i = s52 * d1i - s51 * d2i;
        orr[0][b] = xr[0] + t1r + t2r;
        oi[0][b] = xi[0] + t1i + t2i;
        orr[1][b] = m1r + sg * e1i;
        oi[1][b] = m1i - sg * e1r;
        orr[4][b] = m1r - sg * e1i;
        oi[4][b] = m1i + sg * e1r;
        orr[2][b] = m2r + sg * e2i;
        oi[2][b] = m2i - sg * e2r;
        orr[3][b] = m2r - sg * e2i;
        oi[3][b] = m2i + sg * e2r;
      }
    }
  }
}

template <bool kInverse>
void RunStage(int radix, int n, int span, const double* twr, const double* twi, const double* ir,
              const double* ii, int is, double* orr, double* oi, int os, int batch) {
  switch (radix) {
    case 2: Stage<2, kInverse>(n, span, twr, twi, ir, ii, is, orr, oi, os, batch); break;
    case 3: Stage<3, kInverse>(n, span, twr, twi, ir, ii, is, orr, oi, os, batch); break;
    case 4: Stage<4, kInverse>(n, span, twr, twi, ir, ii, is, orr, oi, os, batch); break;
    default: Stage<5, kInverse>(n, span, twr, twi, ir, ii, is, orr, oi, os, batch); break;
  }
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
  while (rest % 4 == 0) { radices.push_back(4); rest /= 4; }
  while (rest % 2 == 0) { radices.push_back(2); rest /= 2; }
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
    stages_.push_back(std::move(s));
    span *= R;
  }
}

void FftPlan::Transform(double* re, double* im, int batch, int stride, bool inverse,
                        double* sre, double* sim) const {
  // Ping-pong between the data (row stride `stride`) and the scratch
  // (compact, row stride `batch`).
  const double* ir = re;
  const double* ii = im;
  int is = stride;
  bool in_data = true;
  for (const Stage& s : stages_) {
    double* orr = in_data ? sre : re;
    double* oi = in_data ? sim : im;
    const int os = in_data ? batch : stride;
    if (inverse) {
      RunStage<true>(s.radix, n_, s.span, s.tw_re.data(), s.tw_im.data(), ir, ii, is, orr, oi, os,
                     batch);
    } else {
      RunStage<false>(s.radix, n_, s.span, s.tw_re.data(), s.tw_im.data(), ir, ii, is, orr, oi,
                      os, batch);
    }
    ir = orr;
    ii = oi;
    is = os;
    in_data = !in_data;
  }
  if (!in_data) {
    for (int k = 0; k < n_; ++k) {
      std::memcpy(re + static_cast<size_t>(k) * stride, sre + static_cast<size_t>(k) * batch,
                  batch * sizeof(double));
      std::memcpy(im + static_cast<size_t>(k) * stride, sim + static_cast<size_t>(k) * batch,
                  batch * sizeof(double));
    }
  }
}

namespace {
// Odd row strides: power-of-two strides put the radix streams of a stage in
// the same cache sets (measured 3-8x slower at 128 and 256).
int PaddedStride(int n) { return n | 1; }

// Scratch for a 2D transform: the y-pass work arrays (W each) and the
// stages' ping-pong arrays (max(W, spectrum) each), in one buffer.
void SplitScratch(size_t W, size_t spectrum, std::vector<double>* scratch, double** wr,
                  double** wi, double** sr, double** si) {
  const size_t S = std::max(W, spectrum);
  scratch->resize(2 * W + 2 * S);
  *wr = scratch->data();
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
  for (int y = 0; y < rows; ++y) {
    std::memcpy(wr + static_cast<size_t>(y) * lw, re + static_cast<size_t>(y) * stride,
                cols * sizeof(double));
    if (im) {
      std::memcpy(wi + static_cast<size_t>(y) * lw, im + static_cast<size_t>(y) * stride,
                  cols * sizeof(double));
    }
  }
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
  for (int y = 0; y < rows; ++y) {
    std::memcpy(re + static_cast<size_t>(y) * stride, wr + static_cast<size_t>(y) * lw,
                cols * sizeof(double));
    if (im) {
      std::memcpy(im + static_cast<size_t>(y) * stride, wi + static_cast<size_t>(y) * lw,
                  cols * sizeof(double));
    }
  }
}

void Fft2D::ForwardReal(const double* re, int stride, int rows, int cols, double* spec_re,
                        double* spec_im, std::vector<double>* scratch) const {
  const int h = (cols + 1) / 2;  // column c is packed with column c + h
  const int lw = PaddedStride(h);
  const size_t W = static_cast<size_t>(ny_) * lw;
  double *wr, *wi, *sr, *si;
  SplitScratch(W, spectrum_size(), scratch, &wr, &wi, &sr, &si);
  std::fill(wr, wr + W, 0.0);
  std::fill(wi, wi + W, 0.0);
  for (int y = 0; y < rows; ++y) {
    const double* row = re + static_cast<size_t>(y) * stride;
    std::memcpy(wr + static_cast<size_t>(y) * lw, row, h * sizeof(double));
    std::memcpy(wi + static_cast<size_t>(y) * lw, row + h, (cols - h) * sizeof(double));
  }
  py_.Transform(wr, wi, h, lw, false, sr, si);
  // Split Z = A + i B (A, B spectra of real columns): A = (Z(k) + conj
  // Z(-k)) / 2, B = (Z(k) - conj Z(-k)) / (2 i); into (x, ky), half ky.
  const int ls = spec_stride_, hy = half_ny();
  for (int c = 0; c < h; ++c) {
    double* ar = spec_re + static_cast<size_t>(c) * ls;
    double* ai = spec_im + static_cast<size_t>(c) * ls;
    double* br = spec_re + static_cast<size_t>(c + h) * ls;
    double* bi = spec_im + static_cast<size_t>(c + h) * ls;
    const bool has_b = c + h < cols;
    for (int ky = 0; ky < hy; ++ky) {
      const size_t k = static_cast<size_t>(ky) * lw + c;
      const size_t m = static_cast<size_t>((ny_ - ky) % ny_) * lw + c;
      const double zr = wr[k], zi = wi[k], mr = wr[m], mi = wi[m];
      ar[ky] = 0.5 * (zr + mr);
      ai[ky] = 0.5 * (zi - mi);
      if (has_b) {
        br[ky] = 0.5 * (zi + mi);
        bi[ky] = -0.5 * (zr - mr);
      }
    }
  }
  for (int x = cols; x < nx_; ++x) {
    std::fill(spec_re + static_cast<size_t>(x) * ls, spec_re + static_cast<size_t>(x) * ls + hy, 0.0);
    std::fill(spec_im + static_cast<size_t>(x) * ls, spec_im + static_cast<size_t>(x) * ls + hy, 0.0);
  }
  px_.Transform(spec_re, spec_im, hy, ls, false, sr, si);
}

void Fft2D::InverseReal(double* spec_re, double* spec_im, int rows, int cols, double* re,
                        int stride, std::vector<double>* scratch) const {
  const int h = (cols + 1) / 2;
  const int lw = PaddedStride(h);
  const size_t W = static_cast<size_t>(ny_) * lw;
  double *wr, *wi, *sr, *si;
  SplitScratch(W, spectrum_size(), scratch, &wr, &wi, &sr, &si);
  const int ls = spec_stride_, hy = half_ny();
  px_.Transform(spec_re, spec_im, hy, ls, true, sr, si);
  // Z = A + i B over the full ky range, the upper half from A(-k) =
  // conj A(k) (the columns' inverses are real).
  for (int c = 0; c < h; ++c) {
    const double* ar = spec_re + static_cast<size_t>(c) * ls;
    const double* ai = spec_im + static_cast<size_t>(c) * ls;
    const bool has_b = c + h < cols;
    const double* br = spec_re + static_cast<size_t>(c + h) * ls;
    const double* bi = spec_im + static_cast<size_t>(c + h) * ls;
    for (int ky = 0; ky < ny_; ++ky) {
      const bool low = ky < hy;
      const int q = low ? ky : ny_ - ky;
      const double sgn = low ? 1.0 : -1.0;  // conjugate in the upper half
      const double a_r = ar[q], a_i = sgn * ai[q];
      const double b_r = has_b ? br[q] : 0.0, b_i = has_b ? sgn * bi[q] : 0.0;
      wr[static_cast<size_t>(ky) * lw + c] = a_r - b_i;
      wi[static_cast<size_t>(ky) * lw + c] = a_i + b_r;
    }
  }
  py_.Transform(wr, wi, h, lw, true, sr, si);
  for (int y = 0; y < rows; ++y) {
    double* row = re + static_cast<size_t>(y) * stride;
    std::memcpy(row, wr + static_cast<size_t>(y) * lw, h * sizeof(double));
    std::memcpy(row + h, wi + static_cast<size_t>(y) * lw, (cols - h) * sizeof(double));
  }
}

}  // namespace mjtouch
