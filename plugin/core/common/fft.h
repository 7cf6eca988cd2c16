// Mixed-radix (2, 3, 4, 5, 8; 2 x 3 and 3 x 3 fused) Stockham FFTs, double
// or float, for the contact solver's convolutions on the taxel grid
// (contact/compliance.*). Pure C++.
//
// Why our own rather than a library: the solver needs 2D transforms of sizes
// just above 2m - 1 for an m-cell contact box (zero padding, DC-FFT); sizes
// with factors 3 and 5 avoid padding to the next power of two (up to 4x the
// work in 2D). The transforms run in "vector mode" (each butterfly over a
// contiguous batch of columns), which the compiler vectorises without
// intrinsics; the per-lane arithmetic does not depend on the batch width or
// the instruction set, so results are bit-identical on every code path.
// Split storage (separate real and imaginary arrays); unnormalised. The
// real transforms also run in float (twice the lanes, half the memory
// traffic): the contact solver's operator is a float table applied to a CG
// with tolerance ~1e-4 (contact/compliance.h).
#ifndef MJTOUCH_COMMON_FFT_H_
#define MJTOUCH_COMMON_FFT_H_

#include <cstddef>
#include <vector>

namespace mjtouch {

// n >= 1 is a product of 2, 3 and 5 only.
bool IsFftSize(int n);
// The smallest such size >= n.
int NextFftSize(int n);

// Batched 1D complex FFT of length n: element k of batch lane b is at
// re[k * stride + b], im[...] (b < batch <= stride). Forward:
// exp(-2 pi i j k / n); inverse: exp(+...) without the 1/n factor. In place;
// sre / sim: scratch of n * (batch rounded up to a multiple of 32 /
// sizeof(T)) elements each (rows on whole 32-byte vectors). T: double or float.
class FftPlan {
 public:
  explicit FftPlan(int n);  // IsFftSize(n)
  int size() const { return n_; }
  // nonzero (< 0: n): only elements k < nonzero of the input are nonzero;
  // at most n / 2 with a leading radix-4 or -2 stage (or 2 fused with 3),
  // that stage skips the zero half (the same bits: x + 0 and x - 0 are x). needed (< 0: n):
  // only outputs k < needed are read afterwards (the others may be left
  // unwritten); at most 3 n / 5 with a trailing radix-5 stage (2 n / 3,
  // radix 3), that stage skips two of its five outputs (one of three).
  // scale (non-null): the input's element k, lane b is first multiplied by
  // scale[k * scale_stride + b] (in the first stage's pass).
  template <typename T>
  void Transform(T* re, T* im, int batch, int stride, bool inverse, T* sre, T* sim,
                 int nonzero = -1, int needed = -1, const T* scale = nullptr,
                 int scale_stride = 0) const;
  // Whether Transform with this `nonzero` skips (never reads) the input's
  // elements k >= n / 2.
  bool SkipsUpperHalf(int nonzero) const {
    return nonzero >= 0 && 2 * nonzero <= n_ && !stages_.empty() &&
           (stages_[0].radix == 4 || stages_[0].radix == 2 || stages_[0].ra == 2);
  }

 private:
  struct Stage {
    int radix = 0;
    int span = 0;  // product of the earlier stages' radices
    // Nonzero: two stages, radix ra (span) then radix / ra (span ra), run
    // as one in registers (fft.cc's FusedStage); tw: the first's table,
    // tw2 the second's.
    int ra = 0;
    std::vector<double> tw_re, tw_im;     // span x radix: exp(-2 pi i r j / (span radix))
    std::vector<float> tw_re_f, tw_im_f;  // the same, rounded to float
    std::vector<double> tw2_re, tw2_im;
    std::vector<float> tw2_re_f, tw2_im_f;
  };
  int n_;
  std::vector<Stage> stages_;
};

// 2D complex FFT of an ny x nx array whose nonzero part is a rows x cols
// block at the origin. The spectrum is stored transposed (kx-major):
// spec[kx * spectrum_stride() + ky], spectrum_size() doubles per part;
// pointwise products in frequency space do not care, and it saves a
// transpose each way.
class Fft2D {
 public:
  Fft2D(int nx, int ny);  // IsFftSize(nx) && IsFftSize(ny)
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  int spectrum_stride() const { return spec_stride_; }
  size_t spectrum_size() const { return static_cast<size_t>(nx_) * spec_stride_; }

  // Input re/im[y * stride + x], y < rows, x < cols (im may be null: zero).
  void Forward(const double* re, const double* im, int stride, int rows, int cols, double* spec_re,
               double* spec_im, std::vector<double>* scratch) const;
  // Destroys the spectrum; writes re/im[y * stride + x] for y < rows,
  // x < cols only (im may be null). No 1/(nx ny) factor.
  void Inverse(double* spec_re, double* spec_im, int rows, int cols, double* re, double* im,
               int stride, std::vector<double>* scratch) const;
  // Real input (a rows x cols block at the origin): the half spectrum ky in
  // [0, half_ny()), stored like Forward's (spec[kx * spectrum_stride() + ky]);
  // the other half is implied by X(-k) = conj X(k). Pairs of real columns
  // share one complex transform along y, and only half the ky lanes are
  // transformed along x: about half of Forward's work.
  // T (spectrum and work arrays): double or float (the input is rounded).
  template <typename T>
  void ForwardReal(const double* re, int stride, int rows, int cols, T* spec_re, T* spec_im,
                   std::vector<T>* scratch) const;
  // Inverse of a half spectrum whose full spectrum is Hermitian (a real
  // field): writes re[y * stride + x] for y < rows, x < cols. Destroys the
  // spectrum. No 1/(nx ny) factor.
  template <typename T>
  void InverseReal(T* spec_re, T* spec_im, int rows, int cols, double* re, int stride,
                   std::vector<T>* scratch) const;
  int half_ny() const { return ny_ / 2 + 1; }
  // out = the convolution of a real field with a real even kernel whose
  // half spectrum (ForwardReal's layout, normalisation included) is k_hat:
  // ForwardReal of the in_rows x in_cols block, the product, InverseReal
  // into out_rows x out_cols. threads > 1: the passes split over
  // ThreadPool::Shared() callers (by columns along y, by ky lanes along x:
  // lanes are independent, so the same bits for any thread count).
  template <typename T>
  void ConvolveReal(const double* in, int in_stride, int in_rows, int in_cols, const T* k_hat,
                    int out_rows, int out_cols, double* out, int out_stride, T* spec_re, T* spec_im,
                    std::vector<T>* scratch, int threads) const;
  // The same with row stride nx (arrays of the full transform size).
  void Forward(const double* re, const double* im, int rows, int cols, double* spec_re,
               double* spec_im, std::vector<double>* scratch) const {
    Forward(re, im, nx_, rows, cols, spec_re, spec_im, scratch);
  }
  void Inverse(double* spec_re, double* spec_im, int rows, int cols, double* re, double* im,
               std::vector<double>* scratch) const {
    Inverse(spec_re, spec_im, rows, cols, re, im, nx_, scratch);
  }

 private:
  // Parts of the real transforms (fft.cc): the y pass over packed columns
  // [c0, c1) in a work slab wr / wi (row stride lw), the x pass over the
  // spectrum's ky lanes [lo, hi) stored at offset with row stride `stride`;
  // sr, si: the scratch of SplitScratch.
  struct Slab {
    int lo, hi;
    size_t offset;
    int stride;
  };
  template <typename T>
  void ForwardColumns(const double* re, int stride, int rows, int cols, int c0, int c1, T* wr,
                      T* wi, int lw, const Slab* slabs, int nslabs, T* spec_re, T* spec_im, T* sr,
                      T* si) const;
  template <typename T>
  void ForwardLanes(int cols, const Slab& sl, T* spec_re, T* spec_im, T* sr, T* si) const;
  template <typename T>
  // k_hat (non-null): the spectrum times the kernel's first (ConvolveReal).
  void InverseLanes(int cols, const Slab& sl, T* spec_re, T* spec_im, T* sr, T* si,
                    const T* k_hat = nullptr) const;
  template <typename T>
  void InverseColumns(T* spec_re, T* spec_im, const Slab* slabs, int nslabs, int rows, int cols,
                      int c0, int c1, double* re, int stride, T* wr, T* wi, int lw, T* sr,
                      T* si) const;

  int nx_, ny_;
  int spec_stride_;
  FftPlan px_, py_;
};

}  // namespace mjtouch

#endif  // MJTOUCH_COMMON_FFT_H_
