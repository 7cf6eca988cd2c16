// Stage 2, `elastic` model: boundary-element contact of the skin against
// rigid counter-surfaces. Find the pressure p >= 0 on the taxel cells with
//   g0 - alpha + u(p) = 0 where p > 0,   g0 - alpha + u(p) >= 0 where p = 0,
//   sum(p) * cell area = W (MuJoCo's normal force),
// where g0 is the rendered gap, alpha the rigid approach and u = K * p the
// skin's normal surface displacement (K: surface compliance of one cell's
// uniform pressure at another cell's centre). Algorithm: Polonsky & Keer
// (1999) constrained conjugate gradient, load-controlled; K * p by FFT with
// zero padding to at least 2m - 1 per axis (non-periodic, DC-FFT: Liu, Wang &
// Liu 2000), or without padding on a periodic grid.
//
// Substrate: SurfaceCompliance below (homogeneous half-space, closed form)
// or any table with the same layout, e.g.
// LayeredSubstrate::SurfaceComplianceTable (layered.h).
#ifndef MJTOUCH_CONTACT_CONTACT_SOLVER_H_
#define MJTOUCH_CONTACT_CONTACT_SOLVER_H_

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "common/fft.h"
#include "common/grid.h"

namespace mjtouch {

// Normal surface displacement (m per Pa) of a homogeneous, isotropic
// half-space at the centre of cell (i, j) of an n x n lattice of pitch
// pitch_m from unit uniform pressure on cell (i + di, j + dj):
// table[(dj + n - 1) * L + (di + n - 1)], L = 2n - 1 (the layout of
// LayeredSubstrate::SurfaceComplianceTable). Closed form (Love 1929; Johnson,
// Contact Mechanics, eq. 3.25): u = p / (pi E*) sum over the corners of
// +-[X asinh(Y/|X|) + Y asinh(X/|Y|)], E* = E / (1 - nu^2).
void HalfSpaceSurfaceComplianceTable(double young_pa, double poisson, double pitch_m, int n,
                                     std::vector<float>* table);

struct ElasticSolveStats {
  int iterations = 0;
  double change = 0;         // last relative L1 pressure change (the stopping test)
  bool converged = false;
  double approach_m = 0;     // alpha: mean of g0 + u over the contact
  double max_contact_gap_m = 0;  // largest g0 among contact cells
  int contact_cells = 0;
  int fft_size_x = 0, fft_size_y = 0;
};

// Per-simulation scratch (no state that outlives a call).
struct ElasticWork {
  std::vector<double> g0, p, u, g, t, r, p_new, delta;
  std::vector<int> changed;
  std::vector<double> spec_re, spec_im, fft_scratch, conv_im;
};

class ElasticContact {
 public:
  // Non-periodic solver for an n x n grid of pitch pitch_m with a compliance
  // table (layout as HalfSpaceSurfaceComplianceTable).
  ElasticContact(int n, double pitch_m, std::vector<float> compliance_table);
  // Periodic solver on an nx x ny grid (IsFftSize of both) with the Fourier
  // surface compliance C(k) (m/Pa per unit wavenumber 1/m; C(0) is ignored:
  // the mean displacement is part of the approach). For oracles such as
  // Westergaard's wavy surface.
  ElasticContact(int nx, int ny, double pitch_m, const std::function<double(double)>& c_of_k);

  bool periodic() const { return periodic_; }
  // Largest upward (negative) surface displacement per Pa of pressure on a
  // cell anywhere (m/Pa, >= 0): a layered skin bulges beside a load. A cell
  // whose gap exceeds the approach by more than this times sum(p) can never
  // touch, which bounds the box a solve needs.
  double max_lift_m_per_pa() const { return max_lift_; }
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  double pitch_m() const { return pitch_m_; }

  // Solve on `box` (periodic: the whole grid). gap_m and pressure_pa are
  // full nx x ny grids (row-major, j * nx + i). Cells with non-finite gap
  // never touch. pressure_pa holds the initial guess on entry (any p >= 0;
  // all zero: uniform over the candidates) and the solution on exit (zero
  // outside the box). Stops when the relative L1 change of the pressure in
  // one iteration is below `tolerance`, or after max_iterations. Returns
  // false if no cell can carry the load.
  bool Solve(const std::vector<double>& gap_m, const CellBox& box, double force_n,
             double tolerance, int max_iterations, std::vector<double>* pressure_pa,
             ElasticWork* work, ElasticSolveStats* stats) const;

  // Displacement u = K * p on the box (for tests and diagnostics).
  void Displacement(const std::vector<double>& pressure_pa, const CellBox& box,
                    std::vector<double>* u_m, ElasticWork* work) const;

 private:
  struct Spectrum {
    Fft2D fft;
    std::vector<double> k_hat;  // real (K is even), already divided by nx ny
    explicit Spectrum(int mx, int my) : fft(mx, my) {}
  };
  std::shared_ptr<const Spectrum> SpectrumFor(int bx, int by) const;
  // out = K * in over a bx x by box (arrays bx * by, row-major).
  void Convolve(const Spectrum& s, const double* in, int bx, int by, double* out,
                ElasticWork* w) const;
  double TableAt(int di, int dj) const {
    return table_[static_cast<size_t>(dj + n_ - 1) * (2 * n_ - 1) + (di + n_ - 1)];
  }

  bool periodic_ = false;
  int nx_ = 0, ny_ = 0, n_ = 0;
  double pitch_m_ = 0;
  std::vector<float> table_;  // non-periodic
  double max_lift_ = 0;
  std::shared_ptr<const Spectrum> periodic_spectrum_;
  mutable std::mutex mu_;
  mutable std::map<std::pair<int, int>, std::shared_ptr<const Spectrum>> spectra_;
};

}  // namespace mjtouch

#endif  // MJTOUCH_CONTACT_CONTACT_SOLVER_H_
