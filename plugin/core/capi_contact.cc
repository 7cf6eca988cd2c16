// C API over stages 1-2 (surface rendering, contact pressure), for Python
// (mjtouch.core) and tests: every function runs without a MuJoCo scene.
// Nothing throws across this boundary; errors are nonzero return codes.
#include <cmath>
#include <cstring>
#include <vector>

#include "contact_solver.h"
#include "pressure.h"
#include "surface.h"

namespace {
using namespace mjtouch;
}  // namespace

extern "C" {

// Half-space surface compliance table (m/Pa), layout as
// HalfSpaceSurfaceComplianceTable: (2n - 1)^2 floats.
__attribute__((visibility("default"))) int mjtouch_surface_compliance(
    double young, double poisson, double pitch_m, int n, float* out) {
  if (!(young > 0) || !(poisson > -1 && poisson <= 0.5) || !(pitch_m > 0) || n < 1) return 1;
  std::vector<float> t;
  HalfSpaceSurfaceComplianceTable(young, poisson, pitch_m, n, &t);
  std::memcpy(out, t.data(), t.size() * sizeof(float));
  return 0;
}

// Elastic (boundary-element) contact of a homogeneous half-space skin on an
// nx x ny grid (row-major j * nx + i). periodic = 0: non-periodic (DC-FFT,
// needs nx == ny); 1: periodic (nx, ny products of 2, 3, 5). gap: m (non-
// finite: cannot touch); pressure: in = initial guess (zeros: none), out =
// solution (Pa). stats: iterations, converged, last change, approach (m),
// contact cells, largest contact gap (m).
__attribute__((visibility("default"))) int mjtouch_elastic_pressure(
    int nx, int ny, double pitch_m, const double* gap, double young, double poisson,
    double force, int periodic, double tolerance, int max_iterations, double* pressure,
    double* stats) {
  if (nx < 1 || ny < 1 || !(pitch_m > 0) || !(young > 0) || !(poisson > -1 && poisson <= 0.5) ||
      !(tolerance > 0) || max_iterations < 1)
    return 1;
  if (!periodic && nx != ny) return 1;
  if (periodic && (!IsFftSize(nx) || !IsFftSize(ny))) return 1;
  const size_t N = static_cast<size_t>(nx) * ny;
  std::vector<double> g(gap, gap + N), p(pressure, pressure + N);
  ElasticWork work;
  ElasticSolveStats st;
  bool ok;
  if (periodic) {
    const double e_star = young / (1.0 - poisson * poisson);
    ElasticContact ec(nx, ny, pitch_m, [&](double k) { return 2.0 / (e_star * k); });
    ok = ec.Solve(g, CellBox{0, 0, nx, ny}, force, tolerance, max_iterations, &p, &work, &st);
  } else {
    std::vector<float> table;
    HalfSpaceSurfaceComplianceTable(young, poisson, pitch_m, nx, &table);
    ElasticContact ec(nx, pitch_m, std::move(table));
    ok = ec.Solve(g, CellBox{0, 0, nx, nx}, force, tolerance, max_iterations, &p, &work, &st);
  }
  std::memcpy(pressure, p.data(), N * sizeof(double));
  stats[0] = st.iterations;
  stats[1] = st.converged;
  stats[2] = st.change;
  stats[3] = st.approach_m;
  stats[4] = st.contact_cells;
  stats[5] = st.max_contact_gap_m;
  return ok ? 0 : 2;
}

}  // extern "C"
