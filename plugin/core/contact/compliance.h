// Stage 2, `elastic` model: the substrate's surface compliance as an
// operator on the taxel grid, u = K * p (u: normal surface displacement, m;
// p: cell pressure, Pa; K: displacement at one cell's centre per Pa of
// uniform pressure on another cell). Applied by FFT: zero-padded to at least
// 2m - 1 per axis on an m-cell box (non-periodic, DC-FFT: Liu, Wang & Liu
// 2000), or without padding on a periodic grid. The solver
// (contact_solver.h) only ever sees this operator.
//
// Built from a (2n - 1)^2 table (substrate/substrate.h
// HalfSpaceSurfaceComplianceTable, LayeredSubstrate::SurfaceComplianceTable)
// or, periodic, from the Fourier compliance C(k).
#ifndef MJTOUCH_CONTACT_COMPLIANCE_H_
#define MJTOUCH_CONTACT_COMPLIANCE_H_

#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "common/fft.h"

namespace mjtouch {

class LayeredSubstrate;

// Arithmetic of SurfaceCompliance::Apply's FFTs. kFloat: the spectra in
// float (the table is float, and the contact solver stops at a relative
// change ~1e-4; float rounding adds ~1e-7 relative to K p): the fast path.
// kDouble: the reference path.
enum class ApplyPrecision { kFloat = 0, kDouble };

// Per-caller FFT scratch (no state that outlives a call).
struct ComplianceWork {
  std::vector<double> spec_re, spec_im, fft_scratch;
  std::vector<float> spec_re_f, spec_im_f, fft_scratch_f;
};

class SurfaceCompliance {
 public:
  // Non-periodic, n x n grid of pitch pitch_m: table[(dj + n - 1) * L +
  // (di + n - 1)], L = 2n - 1, m/Pa (layout of HalfSpaceSurfaceComplianceTable).
  SurfaceCompliance(int n, double pitch_m, std::vector<float> table);
  // Periodic nx x ny grid (IsFftSize of both) with the Fourier surface
  // compliance C(k) (m/Pa per unit wavenumber 1/m; C(0) is ignored: the mean
  // displacement is part of the approach). For oracles such as Westergaard's
  // wavy surface.
  SurfaceCompliance(int nx, int ny, double pitch_m, const std::function<double(double)>& c_of_k);

  bool periodic() const { return periodic_; }
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  double pitch_m() const { return pitch_m_; }
  // Largest upward (negative) surface displacement per Pa of pressure on a
  // cell anywhere (m/Pa, >= 0): a layered skin bulges beside a load.
  double max_lift_m_per_pa() const { return max_lift_; }

  // The kernel's spectrum on the FFT grid for a bx x by box (periodic: the
  // whole grid), built once per FFT size and shared (thread-safe).
  struct Spectrum {
    Fft2D fft;
    std::vector<double> k_hat;   // real (K is even), already divided by nx ny
    std::vector<float> k_hat_f;  // the same rounded to float (ApplyPrecision::kFloat)
    // The inverse operator on this FFT grid (1 / k_hat, Pa/m) in real space,
    // truncated to offsets |di|, |dj| <= kInverseHalfWidth: the contact
    // solver's preconditioner. The inverse of a 1/r-like kernel is nearly
    // local (a half-space's decays as 1/r^3), so a few cells carry it.
    std::vector<double> inverse;  // (2w + 1)^2, [(dj + w) * (2w + 1) + di + w]
    explicit Spectrum(int mx, int my) : fft(mx, my) {}
  };
  // w of Spectrum::inverse. Measured on slide_grating (128 x 0.1 mm,
  // layered skin, last-step warm start, restarts on new contacts): w = 1, 2,
  // 3, 5 took 8, 7.5, 7, 7 median iterations; the full inverse (by FFT) 7,
  // at the cost of a second FFT pair per iteration.
  static constexpr int kInverseHalfWidth = 2;
  std::shared_ptr<const Spectrum> SpectrumFor(int bx, int by) const {
    return SpectrumForReach(bx - 1, by - 1);
  }
  // The spectrum on the smallest FFT grid on which offsets up to reach_x,
  // reach_y cells (input to output) do not wrap: 2 reach + 1 per axis.
  std::shared_ptr<const Spectrum> SpectrumForReach(int reach_x, int reach_y) const;
  // out = K * in over a bx x by box (arrays bx * by, row-major), with the
  // spectrum from SpectrumFor(bx, by). in_rows, in_cols (<= by, bx; default
  // all): in is zero outside its first in_rows x in_cols block (fewer input
  // columns to transform; a spectrum of a smaller reach then suffices).
  // threads: ThreadPool callers of the FFTs (the same bits for any count).
  void Apply(const Spectrum& s, const double* in, int bx, int by, double* out, ComplianceWork* w,
             ApplyPrecision precision, int threads, int in_rows = -1, int in_cols = -1) const;
  // u += K * (d on cell c of the box) by direct sum (non-periodic only):
  // cheaper than an FFT when few cells change.
  void AddCell(int c, double d, int bx, int by, double* u) const {
    AddCellAt(c % bx, c / bx, d, bx, by, u);
  }
  // The same for the cell (ci, cj) in box coordinates, inside the box or
  // not (on the operator's grid).
  void AddCellAt(int ci, int cj, double d, int bx, int by, double* u) const {
    AddCellRows(ci, cj, d, bx, 0, by, u);
  }
  // AddCell for cells[0..count) in order with amounts d[cells[k]], the box's
  // rows split over `threads` ThreadPool callers (each element sums the
  // cells in list order: the same bits for any count).
  void AddCells(const int* cells, size_t count, const double* d, int bx, int by, double* u,
                int threads) const;
  // AddCellAt for the cells (ci[k], cj[k]) (box coordinates, inside the box
  // or not), k < count in order, amounts d[k]; rows split as in AddCells.
  void AddCellsAt(const int* ci, const int* cj, const double* d, size_t count, int bx, int by,
                  double* u, int threads) const;

 private:
  // Fills s->inverse from s->k_hat (modes with k_hat <= 0 dropped: the
  // periodic operator's mean is part of the approach).
  static void BuildInverse(Spectrum* s);
  // AddCellAt over the box rows [j0, j1) only.
  void AddCellRows(int ci, int cj, double d, int bx, int j0, int j1, double* u) const;
  // AddCellRows for kCells cells in one pass over u (each element adds them
  // in order: kCells AddCellRows' bits, 1 / kCells of the loads and stores).
  template <int kCells>
  void AddCellRowsN(const int* ci, const int* cj, const double* d, int bx, int j0, int j1,
                    double* u) const;
  // AddCellsAt over the box rows [j0, j1) in blocks of rows (the block of u
  // stays in L1 while the cells' table rows stream past); cell(k, &ci, &cj,
  // &d) gives the k-th cell.
  template <typename Cell>
  void AddCellBlocks(size_t count, const Cell& cell, int bx, int j0, int j1, double* u) const;
  double TableAt(int di, int dj) const {
    return table_[static_cast<size_t>(dj + n_ - 1) * (2 * n_ - 1) + (di + n_ - 1)];
  }

  bool periodic_ = false;
  int nx_ = 0, ny_ = 0, n_ = 0;
  double pitch_m_ = 0;
  std::vector<float> table_;  // non-periodic, m/Pa, (2n - 1)^2
  // table_ with each row reversed (the direct sums walk it forward: no
  // lane reversals in their loops; float: half the cache traffic, and each
  // value widens to double exactly)
  std::vector<float> table_rev_;
  double max_lift_ = 0;
  std::shared_ptr<const Spectrum> periodic_spectrum_;
  mutable std::mutex mu_;
  mutable std::map<std::pair<int, int>, std::shared_ptr<const Spectrum>> spectra_;
};

// How many cells' AddCell (box_cells multiply-adds each) cost about one
// Apply with spectrum s, taking one FFT flop (5 N log2 N) to cost as much as
// ~4 multiply-adds.
inline double DirectCellsPerApply(const SurfaceCompliance::Spectrum& s, size_t box_cells) {
  const double n = static_cast<double>(s.fft.nx()) * s.fft.ny();
  return 5.0 * n * std::log2(n) / (4.0 * static_cast<double>(box_cells));
}

// The operators of the two skins on an n x n grid of pitch pitch_m.
std::shared_ptr<const SurfaceCompliance> HalfSpaceCompliance(double young_pa, double poisson,
                                                             double pitch_m, int n);
std::shared_ptr<const SurfaceCompliance> LayeredCompliance(const LayeredSubstrate& substrate,
                                                           double pitch_m, int n);

}  // namespace mjtouch

#endif  // MJTOUCH_CONTACT_COMPLIANCE_H_
