// Stage 2b: partial slip. Given the normal solution (cell pressure, Pa), the
// friction coefficient mu and the total tangential force (N) MuJoCo reports,
// the tangential tractions q (Pa) with Coulomb's law per cell: stick where
// the skin surface moves with the counter-body (slip increment zero, |q| <=
// mu p), slip where |q| = mu p and q points along the slip increment. The
// tractions sum to the prescribed force; the rigid shift is its multiplier.
// Memory: the previous step's tractions and shift (TangentialState), so that
// a load reversal gives Mindlin-Deresiewicz hysteresis.
//
// Normal first, then tangential (Johnson's approximation, as Kalker's
// CONTACT does): the coupling (1 - 2 nu) / (2 (1 - nu)) is 0.17 at nu 0.4
// and 0 at 0.5, and the counter-body is rigid.
//
//   winkler  local springs q = k_t u (FASTSIM): each cell's trial traction
//            q_prev + k_t dW clamped to the disk |q| <= mu p; the shift
//            increment dW (2-D) by a safeguarded Newton solve. O(loaded cells).
//   elastic  the homogeneous half-space's Cerruti surface compliance
//            (TangentialCompliance), by FFT on the contact's box (DC-FFT
//            zero padding); active-set semismooth Newton steps, each a
//            projected conjugate gradient solve (stick cells free, slip
//            cells free across their slip direction, the force constraint's
//            multiplier the shift), then a projected step onto the disks
//            that updates the sets.
//
// Deterministic: one thread, fixed cell order.
#ifndef MJTOUCH_CONTACT_TANGENTIAL_H_
#define MJTOUCH_CONTACT_TANGENTIAL_H_

#include <array>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "common/fft.h"
#include "common/grid.h"
#include "contact/compliance.h"  // ApplyPrecision

namespace mjtouch {

// The memory carried from step to step (plugin_state): the tangential
// tractions of the last step (Pa, n * n, empty: none yet) and the rigid
// tangential shift of the counter-body relative to the skin's base (m).
// Only shift increments enter the solution. support: when support_known,
// the tractions are zero outside it, so that a step reads and clears that
// box only (the solvers keep it; unknown: the whole grid).
struct TangentialState {
  std::vector<double> shear_x_pa, shear_y_pa;
  double shift_x_m = 0, shift_y_m = 0;
  CellBox support;
  bool support_known = false;
};

// One step's outputs besides the new state.
struct TangentialResult {
  std::vector<unsigned char> stick;  // n * n: 1 stick, 0 slip or unloaded
  int loaded_cells = 0;              // cells with p > 0
  int stick_cells = 0;
  double stuck_share = 0;    // stick_cells / loaded_cells (0 without load)
  bool full_slip = false;    // |F| >= mu P: q = p F / P on every loaded cell
  int iterations = 0;        // elastic: CG iterations; winkler: Newton steps
  int projection_steps = 0;  // Newton steps of the force projections, in all
  double change = 0;         // elastic: last relative L1 change of q
};

// The half-space's tangential surface compliance on an n x n grid of pitch
// pitch_m: displacement u_a at a cell's centre (m) per Pa of uniform shear
// q_b on another cell, from the Cerruti point solution
//   u_x = Q / (2 pi G) [(1 - nu) / r + nu x^2 / r^3],  u_y = Q / (2 pi G) nu x y / r^3
// integrated over the cell in closed form (corner sums of
// x asinh(y/|x|), y asinh(x/|y|) and r). The normal displacement a shear
// load makes, (1 - 2 nu) / (4 pi G) x / r^2, is dropped (see above).
class TangentialCompliance {
 public:
  TangentialCompliance(double young_pa, double poisson, double pitch_m, int n);

  int n() const { return n_; }
  double pitch_m() const { return pitch_m_; }
  // Table entries (m/Pa) at offset (di, dj) = field cell - source cell, |di|, |dj| < n.
  double Kxx(int di, int dj) const { return At(kxx_, di, dj); }
  double Kyy(int di, int dj) const { return At(kyy_, di, dj); }
  double Kxy(int di, int dj) const { return At(kxy_, di, dj); }

  // The three kernels' spectra on an mx x my FFT grid (shared, thread-safe).
  struct Spectra {
    Fft2D fft;
    std::vector<double> xx, yy, xy;       // real, divided by mx my
    std::vector<float> xx_f, yy_f, xy_f;  // the same rounded to float
    Spectra(int mx, int my) : fft(mx, my) {}
  };
  std::shared_ptr<const Spectra> SpectraFor(int bx, int by) const;

  // Work arrays of Apply (per caller).
  struct Work {
    std::vector<double> sxr, sxi, syr, syi, scratch;
    std::vector<float> sxr_f, sxi_f, syr_f, syi_f, scratch_f;
  };
  // (ux, uy) = K * (qx, qy) on a bx x by box (row-major arrays, no wrap).
  // kFloat: spectra in float (~1e-7 of u; the solver's tolerance is far above).
  void Apply(const Spectra& s, const double* qx, const double* qy, int bx, int by, double* ux,
             double* uy, Work* w, ApplyPrecision precision = ApplyPrecision::kDouble) const;

  // A local approximate inverse of K (Pa/m): the 3 x 3 centre of the
  // inverse operator's kernels (offset (di, dj) at [(dj + 1) * 3 + di + 1]),
  // positive definite (else the xy part dropped, else none: `empty`), for
  // preconditioning. Built on first use (thread-safe).
  struct LocalInverse {
    std::array<double, 9> xx{}, yy{}, xy{};
    bool empty = true;
  };
  const LocalInverse& local_inverse() const;

 private:
  double At(const std::vector<double>& t, int di, int dj) const {
    return t[static_cast<size_t>(dj + n_ - 1) * (2 * n_ - 1) + (di + n_ - 1)];
  }
  int n_;
  double pitch_m_;
  std::vector<double> kxx_, kyy_, kxy_;  // (2n - 1)^2, m/Pa
  mutable std::mutex mu_;
  mutable std::map<std::pair<int, int>, std::shared_ptr<const Spectra>> spectra_;
  mutable std::once_flag local_inverse_once_;
  mutable LocalInverse local_inverse_;
};

// The Winkler skin's tangential spring stiffness per area (Pa/m) matching
// its normal one the way a half-space's rigid-punch stiffnesses do
// (tangential 8 G a / (2 - nu), normal 4 G a / (1 - nu)):
// k_t = k_n 2 (1 - nu) / (2 - nu) (0.68 k_n at nu 0.48).
double WinklerTangentialStiffness(double normal_stiffness_pa_per_m, double poisson);

// Checks shared by both solvers; an empty string when valid, else what is
// wrong and its valid range. pressure_box: the pressure is zero outside it
// (null: the whole grid is checked).
std::string CheckTangentialInputs(const TaxelGrid& grid, const std::vector<double>& pressure_pa,
                                  double mu, double fx_n, double fy_n, const TangentialState& state,
                                  const CellBox* pressure_box = nullptr);

// Winkler / FASTSIM partial slip: updates *state (tractions, shift) in
// place and fills *result. The tractions sum to (fx_n, fy_n) to round-off.
// pressure_box: the pressure is zero outside it (null: anywhere). Returns
// false (with *error) on invalid input.
bool SolveTangentialWinkler(const TaxelGrid& grid, const std::vector<double>& pressure_pa,
                            double mu, double fx_n, double fy_n,
                            double tangential_stiffness_pa_per_m, TangentialState* state,
                            TangentialResult* result, std::string* error,
                            const CellBox* pressure_box = nullptr);

// Elastic half-space partial slip on K (same grid). tolerance: relative L1
// change of q per iteration at which to stop; max_iterations caps the CG.
bool SolveTangentialElastic(const TaxelGrid& grid, const std::vector<double>& pressure_pa,
                            double mu, double fx_n, double fy_n, const TangentialCompliance& K,
                            double tolerance, int max_iterations, TangentialState* state,
                            TangentialResult* result, std::string* error,
                            ApplyPrecision precision = ApplyPrecision::kDouble,
                            const CellBox* pressure_box = nullptr);

}  // namespace mjtouch

#endif  // MJTOUCH_CONTACT_TANGENTIAL_H_
