#include "contact/compliance.h"

#include <algorithm>
#include <cmath>

#include "common/simd.h"
#include "common/thread_pool.h"
#include "substrate/layered.h"
#include "substrate/substrate.h"

namespace mjtouch {
namespace {

constexpr double kPi = 3.14159265358979323846;

// SurfaceCompliance::Apply in T, the arithmetic of the spectra: the kernel's
// half spectrum k_hat and the spectrum and FFT scratch buffers, all in T.
// Real field, real even kernel: half spectra (Fft2D::ConvolveReal).
template <typename T>
void ApplyIn(const Fft2D& fft, const std::vector<T>& k_hat, const double* in, int bx, int by,
             int in_rows, int in_cols, double* out, std::vector<T>* spec_re,
             std::vector<T>* spec_im, std::vector<T>* scratch, int threads) {
  const size_t S = fft.spectrum_size();
  spec_re->resize(S);
  spec_im->resize(S);
  fft.ConvolveReal(in, bx, in_rows, in_cols, k_hat.data(), by, bx, out, bx, spec_re->data(),
                   spec_im->data(), scratch, threads);
}

}  // namespace

SurfaceCompliance::SurfaceCompliance(int n, double pitch_m, std::vector<float> table)
    : periodic_(false), nx_(n), ny_(n), n_(n), pitch_m_(pitch_m), table_(std::move(table)) {
  for (float v : table_) max_lift_ = std::max(max_lift_, -static_cast<double>(v));
  const size_t w = 2 * static_cast<size_t>(n) - 1;
  table_rev_.resize(table_.size());
  for (size_t r = 0; r < table_.size() / w; ++r)
    for (size_t m = 0; m < w; ++m) table_rev_[r * w + m] = table_[r * w + (w - 1 - m)];
}

SurfaceCompliance::SurfaceCompliance(int nx, int ny, double pitch_m,
                                     const std::function<double(double)>& c_of_k)
    : periodic_(true), nx_(nx), ny_(ny), n_(0), pitch_m_(pitch_m) {
  auto s = std::make_shared<Spectrum>(nx, ny);
  s->k_hat.assign(s->fft.spectrum_size(), 0.0);
  const int ls = s->fft.spectrum_stride();
  const double norm = 1.0 / (static_cast<double>(nx) * ny);
  for (int kx = 0; kx < nx; ++kx) {
    const int fx = kx <= nx / 2 ? kx : kx - nx;
    for (int ky = 0; ky < ny; ++ky) {
      const int fy = ky <= ny / 2 ? ky : ky - ny;
      if (fx == 0 && fy == 0) continue;
      const double k = 2.0 * kPi * std::hypot(fx / (nx * pitch_m), fy / (ny * pitch_m));
      s->k_hat[static_cast<size_t>(kx) * ls + ky] = c_of_k(k) * norm;
    }
  }
  s->k_hat_f.assign(s->k_hat.begin(), s->k_hat.end());
  BuildInverse(s.get());
  periodic_spectrum_ = std::move(s);
}

void SurfaceCompliance::BuildInverse(Spectrum* s) {
  // k_hat holds the kernel's DFT / (mx my); the inverse kernel's DFT is
  // 1 / DFT = norm / k_hat, and the unnormalised inverse FFT needs norm again.
  const int mx = s->fft.nx(), my = s->fft.ny(), w = kInverseHalfWidth;
  const double norm = 1.0 / (static_cast<double>(mx) * my);
  std::vector<double> re(s->fft.spectrum_size()), im(s->fft.spectrum_size(), 0.0), scratch;
  for (size_t k = 0; k < re.size(); ++k) re[k] = s->k_hat[k] > 0.0 ? norm / s->k_hat[k] : 0.0;
  const int rows = std::min(w + 1, my), cols = std::min(w + 1, mx);
  std::vector<double> corner(static_cast<size_t>(rows) * cols);
  s->fft.InverseReal(re.data(), im.data(), rows, cols, corner.data(), cols, &scratch);
  // Even in both axes: the corner [0, w]^2 gives every offset.
  const int L = 2 * w + 1;
  s->inverse.assign(static_cast<size_t>(L) * L, 0.0);
  for (int dj = -w; dj <= w; ++dj)
    for (int di = -w; di <= w; ++di) {
      const int aj = std::abs(dj), ai = std::abs(di);
      if (aj < rows && ai < cols)
        s->inverse[static_cast<size_t>(dj + w) * L + di + w] =
            corner[static_cast<size_t>(aj) * cols + ai] * norm;
    }
}

std::shared_ptr<const SurfaceCompliance::Spectrum> SurfaceCompliance::SpectrumForReach(
    int reach_x, int reach_y) const {
  if (periodic_) return periodic_spectrum_;
  const int mx = NextFftSize(2 * reach_x + 1), my = NextFftSize(2 * reach_y + 1);
  std::lock_guard<std::mutex> lock(mu_);
  auto& slot = spectra_[{mx, my}];
  if (slot) return slot;
  // The kernel wrapped onto the mx x my torus: offsets up to the box size
  // matter; it is even in both axes, so its transform is real.
  auto s = std::make_shared<Spectrum>(mx, my);
  std::vector<double> kr(static_cast<size_t>(mx) * my, 0.0);
  for (int y = 0; y < my; ++y) {
    const int dy = y <= my / 2 ? y : y - my;
    if (std::abs(dy) > n_ - 1) continue;
    for (int x = 0; x < mx; ++x) {
      const int dx = x <= mx / 2 ? x : x - mx;
      if (std::abs(dx) > n_ - 1) continue;
      kr[static_cast<size_t>(y) * mx + x] = TableAt(dx, dy);
    }
  }
  std::vector<double> sre(s->fft.spectrum_size()), sim(s->fft.spectrum_size()), scratch;
  s->fft.Forward(kr.data(), nullptr, mx, my, mx, sre.data(), sim.data(), &scratch);
  const double norm = 1.0 / (static_cast<double>(mx) * my);
  s->k_hat.resize(sre.size());
  for (size_t k = 0; k < sre.size(); ++k) s->k_hat[k] = sre[k] * norm;
  s->k_hat_f.assign(s->k_hat.begin(), s->k_hat.end());
  BuildInverse(s.get());
  slot = std::move(s);
  return slot;
}

void SurfaceCompliance::Apply(const Spectrum& s, const double* in, int bx, int by, double* out,
                              ComplianceWork* w, ApplyPrecision precision, int threads, int in_rows,
                              int in_cols) const {
  if (in_rows < 0) in_rows = by;
  if (in_cols < 0) in_cols = bx;
  if (precision == ApplyPrecision::kFloat) {
    ApplyIn(s.fft, s.k_hat_f, in, bx, by, in_rows, in_cols, out, &w->spec_re_f, &w->spec_im_f,
            &w->fft_scratch_f, threads);
  } else {
    ApplyIn(s.fft, s.k_hat, in, bx, by, in_rows, in_cols, out, &w->spec_re, &w->spec_im,
            &w->fft_scratch, threads);
  }
}

MJTOUCH_TARGET_CLONES
void SurfaceCompliance::AddCellRows(int ci, int cj, double d, int bx, int j0, int j1,
                                    double* u) const {
  for (int j = j0; j < j1; ++j) {
    double* urow = u + static_cast<size_t>(j) * bx;
    // K(ci - i, cj - j) = table_rev_ at column n - 1 - ci + i
    const float* krow =
        table_rev_.data() + static_cast<size_t>(cj - j + n_ - 1) * (2 * n_ - 1) + (n_ - 1 - ci);
    for (int i = 0; i < bx; ++i) urow[i] += d * static_cast<double>(krow[i]);
  }
}

template <int kCells>
MJTOUCH_TARGET_CLONES void SurfaceCompliance::AddCellRowsN(const int* ci, const int* cj,
                                                           const double* d, int bx, int j0, int j1,
                                                           double* u) const {
  const size_t w = 2 * static_cast<size_t>(n_) - 1;
  double dk[kCells];
  for (int k = 0; k < kCells; ++k) dk[k] = d[k];
  for (int j = j0; j < j1; ++j) {
    double* __restrict urow = u + static_cast<size_t>(j) * bx;
    const float* __restrict kr[kCells];
    for (int k = 0; k < kCells; ++k)
      kr[k] = table_rev_.data() + static_cast<size_t>(cj[k] - j + n_ - 1) * w + (n_ - 1 - ci[k]);
    for (int i = 0; i < bx; ++i) {
      double v = urow[i];
#pragma GCC unroll 8
      for (int k = 0; k < kCells; ++k) v = v + dk[k] * static_cast<double>(kr[k][i]);
      urow[i] = v;
    }
  }
}

template <typename Cell>
void SurfaceCompliance::AddCellBlocks(size_t count, const Cell& cell, int bx, int j0, int j1,
                                      double* u) const {
  constexpr int kRows = 8;
  for (int jb = j0; jb < j1; jb += kRows) {
    const int je = std::min(j1, jb + kRows);
    size_t k = 0;
    for (; k + 8 <= count; k += 8) {
      int ci[8], cj[8];
      double d[8];
      for (int l = 0; l < 8; ++l) cell(k + l, &ci[l], &cj[l], &d[l]);
      AddCellRowsN<8>(ci, cj, d, bx, jb, je, u);
    }
    for (; k + 4 <= count; k += 4) {
      int ci[4], cj[4];
      double d[4];
      for (int l = 0; l < 4; ++l) cell(k + l, &ci[l], &cj[l], &d[l]);
      AddCellRowsN<4>(ci, cj, d, bx, jb, je, u);
    }
    for (; k < count; ++k) {
      int ci, cj;
      double d;
      cell(k, &ci, &cj, &d);
      AddCellRows(ci, cj, d, bx, jb, je, u);
    }
  }
}

void SurfaceCompliance::AddCells(const int* cells, size_t count, const double* d, int bx, int by,
                                 double* u, int threads) const {
  auto cell = [&](size_t k, int* ci, int* cj, double* dk) {
    const int c = cells[k];
    *ci = c % bx;
    *cj = c / bx;
    *dk = d[c];
  };
  ForRowParts(by, threads, 8, [&](int j0, int j1) { AddCellBlocks(count, cell, bx, j0, j1, u); });
}

void SurfaceCompliance::AddCellsAt(const int* ci, const int* cj, const double* d, size_t count,
                                   int bx, int by, double* u, int threads) const {
  auto cell = [&](size_t k, int* i, int* j, double* dk) {
    *i = ci[k];
    *j = cj[k];
    *dk = d[k];
  };
  ForRowParts(by, threads, 8, [&](int j0, int j1) { AddCellBlocks(count, cell, bx, j0, j1, u); });
}

std::shared_ptr<const SurfaceCompliance> HalfSpaceCompliance(double young_pa, double poisson,
                                                             double pitch_m, int n) {
  std::vector<float> table;
  HalfSpaceSurfaceComplianceTable(young_pa, poisson, pitch_m, n, &table);
  return std::make_shared<SurfaceCompliance>(n, pitch_m, std::move(table));
}

std::shared_ptr<const SurfaceCompliance> LayeredCompliance(const LayeredSubstrate& substrate,
                                                           double pitch_m, int n) {
  std::vector<float> table;
  substrate.SurfaceComplianceTable(pitch_m, n, &table);
  return std::make_shared<SurfaceCompliance>(n, pitch_m, std::move(table));
}

}  // namespace mjtouch
