// Stage 2, `elastic` model: boundary-element contact of the skin against
// rigid counter-surfaces. Find the pressure p >= 0 on the taxel cells with
//   g0 - alpha + u(p) = 0 where p > 0,   g0 - alpha + u(p) >= 0 where p = 0,
//   sum(p) * cell area = W (MuJoCo's normal force),
// where g0 is the rendered gap, alpha the rigid approach and u = K * p the
// skin's normal surface displacement (K: the substrate's SurfaceCompliance,
// compliance.h). Algorithm: Polonsky & Keer (1999) constrained conjugate
// gradient, load-controlled; by default preconditioned (kPreconditioned
// below), with P&K's plain iteration kept as the reference path.
//
// Separated as in ContactMechanics / Tamaas: the substrate's Green's function
// (substrate/), the compliance operator on the grid (compliance.h), and this
// solver, a function of the operator, the gap and the load.
#ifndef MJTOUCH_CONTACT_CONTACT_SOLVER_H_
#define MJTOUCH_CONTACT_CONTACT_SOLVER_H_

#include <memory>
#include <vector>

#include "common/grid.h"
#include "contact/compliance.h"

namespace mjtouch {

// kPreconditioned: the CG on the contact set preconditioned by the inverse
// operator's local stencil (SurfaceCompliance::Spectrum::inverse), after
// Vollebregt (2014, J. Optim. Theory Appl. 162: an FFT-derived approximate
// inverse of the influence matrix); cells that overlap (zero pressure,
// negative gap) join the set without a restart (a direction that stops
// descending falls back to the preconditioned gradient), and the search
// direction is projected onto zero net load. On slide_grating (layered skin,
// 128 x 0.1 mm) with the plugin's warm starts: 5 median iterations against
// P&K's 15-16 to the same stopping test, at a lower error against a tight
// reference (examples/bench_elastic.py, tests/unit/test_contact_solver.py).
// kPolonskyKeer: Polonsky & Keer (1999) as published.
enum class ElasticMethod { kPreconditioned = 0, kPolonskyKeer };

// How one solve runs: it stops when the relative L1 change of the pressure
// in one iteration is below `tolerance`, or after max_iterations; `method`;
// the arithmetic of the operator's FFTs (compliance.h; the iteration itself
// is double); the ThreadPool callers of the FFTs and the preconditioner's
// stencil (the same bits for any count).
struct ElasticSolveOptions {
  double tolerance = 1e-4;
  int max_iterations = 500;
  ElasticMethod method = ElasticMethod::kPreconditioned;
  ApplyPrecision precision = ApplyPrecision::kDouble;
  int threads = 1;
};

struct ElasticSolveStats {
  int iterations = 0;
  double change = 0;  // last relative L1 pressure change (the stopping test)
  bool converged = false;
  double approach_m = 0;         // alpha: mean of g0 + u over the contact
  double max_contact_gap_m = 0;  // largest g0 among contact cells
  int contact_cells = 0;
  int fft_size_x = 0, fft_size_y = 0;
  int applies = 0;  // compliance operator applications by FFT (the cost)
};

// Per-simulation scratch (no state that outlives a call).
struct ElasticWork {
  std::vector<double> g0, p, u, g, t, r, p_new, delta;
  std::vector<double> g_pad;        // preconditioner input with a zero border
  std::vector<float> g_pad_f;       // the same in float (ApplyPrecision::kFloat)
  std::vector<int> set;             // kPreconditioned: the cells of the working set
  std::vector<size_t> set_rows;     // where each box row's cells start in set
  std::vector<int> set_lo, set_hi;  // each box row's span of set cells [lo, hi)
  // g, K^-1 g, t, t's last value, p and the step's p on the working set,
  // contiguous (index k of set; contact/working_set.h)
  std::vector<double> set_g, set_z, set_t, set_t_old, set_p, set_p_new;
  std::vector<int> changed;
  std::vector<int> set_changed;  // kPreconditioned: the step's clipped cells
  std::vector<int> dropped;      // the guess's cells the solve drops
  ComplianceWork fft;
};

// Solve on `box` (periodic operator: the whole grid). gap_m and pressure_pa
// are full nx x ny grids of the operator (row-major, j * nx + i). Cells with
// non-finite gap never touch. pressure_pa holds the initial guess on entry
// (any p >= 0; all zero: uniform over the candidates) and the solution on
// exit (zero outside the box). Returns false if no cell can carry the load.
// initial_u_m: if not
// null (kPreconditioned, non-periodic), K times the initial guess on the box
// (bx * by, the guess's cells outside the box left out), which spares the
// solve's first operator application; the solver corrects it for the cells
// it drops (no candidates) and scales it with the guess.
bool SolveElasticContact(const SurfaceCompliance& compliance, const std::vector<double>& gap_m,
                         const CellBox& box, double force_n, const ElasticSolveOptions& options,
                         std::vector<double>* pressure_pa, ElasticWork* work,
                         ElasticSolveStats* stats, const double* initial_u_m = nullptr);

// One skin's elastic contact: its compliance operator (shared, immutable,
// spectra cached per box size) bound to the solver.
class ElasticContact {
 public:
  explicit ElasticContact(std::shared_ptr<const SurfaceCompliance> compliance);

  const SurfaceCompliance& compliance() const { return *compliance_; }
  // Largest upward surface displacement per Pa on a cell (m/Pa, >= 0). A
  // cell whose gap exceeds the approach by more than this times sum(p) can
  // never touch, which bounds the box a solve needs.
  double max_lift_m_per_pa() const { return compliance_->max_lift_m_per_pa(); }

  // SolveElasticContact with this skin's operator.
  bool Solve(const std::vector<double>& gap_m, const CellBox& box, double force_n,
             const ElasticSolveOptions& options, std::vector<double>* pressure_pa,
             ElasticWork* work, ElasticSolveStats* stats,
             const double* initial_u_m = nullptr) const;

 private:
  std::shared_ptr<const SurfaceCompliance> compliance_;
};

}  // namespace mjtouch

#endif  // MJTOUCH_CONTACT_CONTACT_SOLVER_H_
